"""Mitsuba 3.9.1 GGX visible-normal sampling: NaN direction and pdf for sample2 = (0, 0.5).

include/mitsuba/render/microfacet.h:407 maps the sample to the unit disk; sample2 = (0, 0.5)
becomes p = (-1, 0), ON the circle with p.y = 0, so p.y and z = safe_sqrt(1 - |p|^2)
(lines 410-414) are both 0 and line 418 ``norm = dr::rcp(sin_theta_i * y + cos_theta_i * z)``
is 1/0: the slope is (0 * inf, ...) = NaN, hence m, wo and bs.pdf are NaN (other samples with
sample2.x = 0 also lie on the circle but keep p.y != 0).  roughconductor masks its weight to 0
but returns bs.pdf = NaN; blendbsdf then forms ``weight * result1 * bs1.pdf`` with result1 = 0
(src/bsdfs/blendbsdf.cpp:151; ``result0 * bs0.pdf`` at line 139), and 0 x NaN = NaN, so a
render gets a NaN sample weight whenever a sampler yields exactly that point.  Beckmann
visible sampling likewise returns an infinite normal for wi below the horizon (line 375:
tan_theta_i < 0), so a one-sided roughconductor returns wo = bs.pdf = NaN there
(src/bsdfs/roughconductor.cpp:250 keeps them; only the weight is masked).

Run: python tests/repro/microfacet_sample_nan.py  -> exit 1 while the bug is present.
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
rough = {"type": "roughconductor", "distribution": "ggx", "alpha": 0.2}
blend = {"type": "blendbsdf", "weight": 0.3, "bsdf_0": {"type": "diffuse"}, "bsdf_1": rough}
si = dr.zeros(mi.SurfaceInteraction3f, 1)
si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
t = math.radians(40)
si.wi = mi.Vector3f(math.sin(t), 0, math.cos(t))
bad = False
for name, spec in (("roughconductor", rough), ("blendbsdf(diffuse, roughconductor)", blend)):
    bsdf = mi.load_dict(spec)
    bs, weight = bsdf.sample(mi.BSDFContext(), si, mi.Float(0.0), mi.Point2f(0.0, 0.5))
    w, p = float(weight.x[0]), float(bs.pdf[0])
    print(f"{name}: sample1 = 0, sample2 = (0, 0.5) -> wo = {bs.wo}, pdf = {p}, weight = {w}")
    bad |= math.isnan(p) or math.isnan(w)
beckmann = mi.load_dict({"type": "roughconductor", "distribution": "beckmann", "alpha": 0.2})
si.wi = mi.Vector3f(math.sin(t), 0, -math.cos(t))           # below the horizon
bs, weight = beckmann.sample(mi.BSDFContext(), si, mi.Float(0.3), mi.Point2f(0.3, 0.6))
print(f"roughconductor (Beckmann), wi below the horizon -> wo = {bs.wo}, pdf = {bs.pdf[0]}, "
      f"weight = {weight.x[0]}")
bad |= math.isnan(float(bs.pdf[0]))
sys.exit(1 if bad else 0)
