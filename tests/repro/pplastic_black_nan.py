"""Mitsuba 3.9.1 pplastic with both reflectances 0: a NaN pdf above the horizon.

src/bsdfs/pplastic.cpp:239 sets ``m_specular_sampling_weight = s_mean / (d_mean + s_mean)``
from the means of specular_reflectance and diffuse_reflectance (roughplastic.cpp:229's line);
with both 0 that is 0/0 = NaN, so prob_specular and prob_diffuse (lines 454-455) and with them
pdf() (line 476) and eval_pdf() are NaN (eval() is a correct 0).  sample() compares
``sample1 < prob_specular`` (line 265), false for NaN, so it always draws the diffuse lobe,
and returns bs.pdf = pdf(bs.wo) = NaN (line 288) with its weight masked to 0 by
``active &= bs.pdf > 0.f`` (lines 289, 292).  The same in every variant, polarized or not.

Run: python tests/repro/pplastic_black_nan.py  -> exit 1 while the bug is present.
"""
import math
import sys

try:                                   # phonglab pins a libLLVM that Dr.Jit can use
    import phonglab.runtime
    phonglab.runtime.configure()
except ImportError:
    pass
import drjit as dr
import mitsuba as mi

mi.set_variant("llvm_ad_rgb")
bsdf = mi.load_dict({"type": "pplastic", "diffuse_reflectance": 0.0,
                     "specular_reflectance": 0.0})
si = dr.zeros(mi.SurfaceInteraction3f, 1)
si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
t = math.radians(40)
si.wi = mi.Vector3f(math.sin(t), 0, math.cos(t))
wo = mi.Vector3f(-0.3, 0.1, math.sqrt(1 - 0.1))
pdf = float(bsdf.pdf(mi.BSDFContext(), si, wo)[0])
value = float(bsdf.eval(mi.BSDFContext(), si, wo).x[0])
bs, weight = bsdf.sample(mi.BSDFContext(), si, 0.3, mi.Point2f(0.4, 0.6))
print(f"black pplastic: eval = {value}, pdf = {pdf}; sample(): bs.pdf = {float(bs.pdf[0])}, "
      f"weight = {float(weight.x[0])} (expected a finite pdf)")
sys.exit(1 if math.isnan(pdf) else 0)
