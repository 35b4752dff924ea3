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

At normal incidence (sin_theta_i = 0, s = 1) norm = 1 / z, so EVERY sample on an edge of
[0, 1]^2 (mapped onto the circle) is 1/0, e.g. sample2 = (0, 0).  At exactly grazing wi
(cos_theta_i = 0) next to a valid lane, the deactivated lane is still sampled and the
visible-normal pdf (line 223) divides by cos_theta(wi) = 0.  All three inputs have measure
zero: a renderer meets them only with a sampler that yields exact edge values or a ray that
meets a surface exactly edge-on.

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
# Normal incidence: sin_theta_i = 0 and s = 1, so norm = 1 / z, and EVERY point of the sample
# square's edge maps onto the circle (z = 0): sample2 = (0, 0) is 1/0 as well.
si.wi = mi.Vector3f(0, 0, 1)
blend_bsdf = mi.load_dict(blend)
bs, weight = blend_bsdf.sample(mi.BSDFContext(), si, mi.Float(0.0), mi.Point2f(0.0, 0.0))
print(f"blendbsdf(diffuse, roughconductor), wi = (0, 0, 1), sample1 = 0, sample2 = (0, 0) -> "
      f"pdf = {bs.pdf[0]}, weight = {weight.x[0]}")
bad |= math.isnan(float(weight.x[0]))
# Exactly grazing wi (cos_theta_i = 0, a measure-zero input) next to a valid lane: the nested
# roughconductor deactivates the grazing lane (roughconductor.cpp:236) but, as another lane is
# active, still samples it, and the visible-normal pdf divides by cos_theta(wi) = 0
# (microfacet.h:223); bs.pdf keeps that NaN, and blendbsdf's 0 x NaN makes the weight NaN.
# (Alone in its call the lane returns early with zeros: roughconductor.cpp:238.)
si2 = dr.zeros(mi.SurfaceInteraction3f, 2)
si2.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
si2.wi = mi.Vector3f([1.0, 0.6], [0.0, 0.0], [0.0, 0.8])
bs, weight = blend_bsdf.sample(mi.BSDFContext(), si2, mi.Float(0.1), mi.Point2f(0.3, 0.6))
print(f"blendbsdf, lanes wi = (1, 0, 0) and (0.6, 0, 0.8), sample1 = 0.1, sample2 = (0.3, 0.6) "
      f"-> pdf = {bs.pdf}, weight = {weight.x}")
bad |= math.isnan(float(weight.x[0]))
sys.exit(1 if bad else 0)
