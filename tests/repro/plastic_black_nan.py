"""Mitsuba 3.9.1 plastic with both reflectances 0: a NaN pdf and NaN samples.

src/bsdfs/plastic.cpp:206 sets ``m_specular_sampling_weight = s_mean / (d_mean + s_mean)``
from the means of specular_reflectance and diffuse_reflectance; with both 0 that is 0/0 = NaN,
so prob_specular (lines 229, 235; 315, 353 in pdf/eval_pdf) is NaN: pdf() and eval_pdf() are
NaN for every direction above the horizon and sample() returns NaN weights (eval() is a
correct 0).  roughplastic has the same line (roughplastic.cpp:229, tests/repro/
roughplastic_black_nan.py).  Mitsuba's path tracer keeps its renders clean (its MIS weight
drops non-finite values, path.cpp:363; a NaN throughput fails its `!= 0` test); a custom
integrator or a guiding density that uses the pdf gets NaN.  A black material is a
legitimate input (a texture that reaches 0, an optimization driving both to 0).

Run: python tests/repro/plastic_black_nan.py  -> exit 1 while the bug is present.
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
bsdf = mi.load_dict({"type": "plastic", "diffuse_reflectance": 0.0,
                     "specular_reflectance": 0.0})
si = dr.zeros(mi.SurfaceInteraction3f, 1)
si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
t = math.radians(40)
si.wi = mi.Vector3f(math.sin(t), 0, math.cos(t))
wo = mi.Vector3f(-0.3, 0.1, math.sqrt(1 - 0.1))
ctx = mi.BSDFContext()
pdf = float(bsdf.pdf(ctx, si, wo)[0])
value = float(bsdf.eval(ctx, si, wo).x[0])
bs, weight = bsdf.sample(ctx, si, 0.7, mi.Point2f(0.3, 0.6))
w = float(weight.x[0])
print(f"black plastic at 40 deg: eval = {value}, pdf = {pdf}, sample weight = {w} "
      f"(expected a finite pdf and weight)")
sys.exit(1 if math.isnan(pdf) or math.isnan(w) else 0)
