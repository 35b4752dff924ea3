"""Mitsuba 3.9.1 Beckmann microfacets: the visible-normal pdf does not integrate to 1 at grazing
incidence, because it uses an approximate Smith G1 while sample() draws the exact distribution.

include/mitsuba/render/microfacet.h:223 gives the visible-normal density
D(m) G1(wi, m) |wi.m| / cos theta_i, which integrates to 1 over m only with the exact Smith
G1 = 2 / (1 + erf(a) + exp(-a^2) / (a sqrt(pi))), a = 1 / (alpha tan theta_i).  For Beckmann,
smith_g1() (lines 346-352) returns a rational approximation ("< 0.35 % rel. error"), so the
pdf integrates to G1_approx / G1_exact: 0.99724 at cos theta_i = 1e-4 and 1.00283 at 0.05
(alpha = 0.3).  sample_visible() (line 368 on) inverts the exact visible distribution, so
roughconductor's pdf (roughconductor.cpp:421) differs from what sample() draws by that
factor: phonglab validate's normalization topic measures int pdf = 0.99723 with every
sample valid at cos theta_i = 1e-4.  GGX (line 354) uses the exact G1 and integrates to 1.

Run: python tests/repro/beckmann_pdf_normalization.py  -> exit 1 while the bug is present.
"""
import math
import sys

try:                                   # phonglab pins a libLLVM that Dr.Jit can use
    import phonglab.runtime
    phonglab.runtime.configure()
except ImportError:
    pass
import mitsuba as mi
import numpy as np
from scipy.special import erf

mi.set_variant("llvm_ad_rgb")
ALPHA = 0.3


def integral(kind, cos_i, n=1200):
    """int pdf(wi, m) dm over the m hemisphere, Gauss-Legendre in (cos theta_m, phi)."""
    distr = mi.MicrofacetDistribution(kind, ALPHA, True)
    x, w = np.polynomial.legendre.leggauss(n)
    mu = 0.5 * (x + 1.0)                                  # cos theta_m in (0, 1)
    phi = np.pi * (x + 1.0)                               # (0, 2 pi)
    mm, pp = np.meshgrid(mu, phi, indexing="ij")
    ww = np.outer(0.5 * w, np.pi * w)
    s = np.sqrt(1.0 - mm ** 2)
    m = mi.Vector3f(*(np.ascontiguousarray(c.ravel()) for c in (s * np.cos(pp), s * np.sin(pp), mm)))
    wi = mi.Vector3f(math.sqrt(1.0 - cos_i ** 2), 0.0, cos_i)
    return float(np.sum(ww.ravel() * np.array(distr.pdf(wi, m), dtype=np.float64)))


def g1_ratio(cos_i):
    a = cos_i / (ALPHA * math.sqrt(1.0 - cos_i ** 2))
    approx = 1.0 if a >= 1.6 else (3.535 * a + 2.181 * a * a) / (1 + 2.276 * a + 2.577 * a * a)
    return approx / (2.0 / (1.0 + erf(a) + math.exp(-a * a) / (a * math.sqrt(math.pi))))


bad = False
for cos_i in (0.5, 0.05, 1e-4):
    beck = integral(mi.MicrofacetType.Beckmann, cos_i)
    ggx = integral(mi.MicrofacetType.GGX, cos_i)
    print(f"cos theta_i = {cos_i:g}: int pdf dm  Beckmann {beck:.5f} (G1 approx/exact "
          f"{g1_ratio(cos_i):.5f})  GGX {ggx:.5f}")
    bad |= abs(beck - 1.0) > 1e-3
sys.exit(1 if bad else 0)
