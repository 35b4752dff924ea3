"""Mitsuba 3.9.1 hg: sampling loses float32 precision for small |g| above its fallback threshold.

src/phase/hg.cpp (commit 478e193a) lines 77-78 invert the HG CDF as
``sqr_term = (1 - g²) / (1 - g + 2 g u)``, ``cos_theta = (1 + g² - sqr_term²) / (2 g)``: the
numerator is a difference of two numbers near 1, whose float32 rounding (~6e-8) is divided by
2g.  The isotropic fallback (line 81) only takes over for |g| < 2⁻²⁴ (dr::Epsilon), so for
2⁻²⁴ ≤ |g| ≲ 1e-3 the sampled cos θ is off by ~u/g: by up to 1.2e-3 at g = 1e-4 and 1e-2 at
g = 1e-5, with a systematic bias (mean -2.9e-3 at g = 1e-5), while sample() reports the pdf of
the cos θ it computed; the sampled directions no longer follow the pdf (phonglab validate hg
--set g=1e-5: chi2 p = 2e-80).  An optimisation of g through 0 (a fit of a nearly isotropic
medium) passes through this range.

Run: python tests/repro/hg_small_g_sampling.py  -> exit 1 while the behaviour is present.
"""
import sys

try:                                   # phonglab pins a libLLVM that Dr.Jit can use
    import phonglab.runtime
    phonglab.runtime.configure()
except ImportError:
    pass
import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
g = 1e-5
phase = mi.load_dict({"type": "hg", "g": g})
n = 1 << 20
rng = np.random.default_rng(1)
u = rng.random((n, 2)).astype(np.float32)
mei = dr.zeros(mi.MediumInteraction3f, n)
mei.wi = mi.Vector3f(0.0, 0.0, 1.0)
mei.sh_frame = mi.Frame3f(mei.wi)
wo, w, pdf = phase.sample(mi.PhaseFunctionContext(None), mei, mi.Float(u[:, 0]),
                          mi.Point2f(mi.Float(u[:, 0]), mi.Float(u[:, 1])))
mu = -np.array(wo.z, dtype=np.float64)           # cos of the scattering angle (forward = 1)
u0 = u[:, 0].astype(np.float64)
sq = (1 - g * g) / (1 - g + 2 * g * u0)
exact = (1 + g * g - sq * sq) / (2 * g)            # the same inversion in float64
err = mu - exact
print(f"g = {g}: max |cos θ error| = {np.abs(err).max():.3g}, mean error = {err.mean():.3g} "
      f"(float64 inversion of the same u)")
sys.exit(1 if np.abs(err).max() > 1e-4 else 0)
