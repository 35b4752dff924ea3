"""Mitsuba 3.9.1 rough-fiber pdf (hair): I0 from a 10-term series, up to 0.57 % too small.

include/mitsuba/core/warp.h:749-758 evaluates the modified Bessel function I0(x) by the first
11 terms of its power series, sum (x^2/4)^k / (k!)^2, k = 0..10; log_i0() (line 762) uses it
for x <= 12 and the asymptotic expansion above.  The truncated series is short by 0.06 % at
x = 10, 0.21 % at 11 and 0.57 % at 12, so square_to_rough_fiber_pdf() (line 771), hair's
longitudinal density M_p, is too small wherever kappa cos(theta_i) cos(theta_o) lies just
below 12 (and jumps there).  hair.cpp's sample() draws M_p by inverting its exact CDF (lines
275-283), so sampling and pdf disagree: phonglab validate measures int pdf = 0.998 with every
sample valid (normalization) and rejects chi2 at theta_i = 60 deg, phi_i = 1 (hair/default,
longitudinal roughness 0.3: kappa = 1/v = 11.8 for the R lobe).

Run: python tests/repro/hair_fiber_pdf_i0.py  -> exit 1 while the bug is present.
"""
import math
import sys

try:                                   # phonglab pins a libLLVM that Dr.Jit can use
    import phonglab.runtime
    phonglab.runtime.configure()
except ImportError:
    pass
import mitsuba as mi
from scipy.special import i0e

mi.set_variant("llvm_ad_rgb")
kappa = 11.8
worst = 0.0
for c_target in (4.0, 10.0, 11.0, 11.7):
    # wi in the plane normal to the tangent y (theta_i = 0), wo at longitudinal angle a:
    # c = kappa cos(theta_i) cos(theta_o) = kappa cos(a), s = kappa sin(theta_i) sin(theta_o) = 0
    a = math.acos(c_target / kappa)
    wi = mi.Vector3f(1.0, 0.0, 0.0)
    wo = mi.Vector3f(math.cos(a), math.sin(a), 0.0)
    got = float(mi.warp.square_to_rough_fiber_pdf(wo, wi, mi.Vector3f(0, 1, 0), kappa)[0])
    c = kappa * math.cos(a)
    # exact: exp(-s) I0(c) kappa / (2 sinh kappa) / (2 pi), s = 0; I0(c) = i0e(c) e^c
    exact = math.exp(c - kappa + math.log(i0e(c))) * kappa / (1.0 - math.exp(-2 * kappa)) \
        / (2 * math.pi)
    rel = got / exact - 1.0
    worst = max(worst, abs(rel))
    print(f"kappa = {kappa}, kappa cos = {c:.2f}: pdf {got:.6g}, exact {exact:.6g}, "
          f"relative {rel:+.2e}")
sys.exit(1 if worst > 1e-3 else 0)
