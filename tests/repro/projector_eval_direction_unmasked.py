"""Mitsuba 3.9.1 projector: eval_direction does not apply the frustum test sample_direction does.

src/emitters/projector.cpp (commit 478e193a): sample_direction sets
``active &= all(uv >= 0 && uv <= 1) && it_local.z() > 0`` (line 212) and returns pdf 0
and weight 0 outside the projection frustum; eval_direction (lines 272-293) evaluates the
texture at ds.uv and divides by it_local.z² · (−n·d) with no such mask, so for a reference point
behind the projector (it_local.z < 0, where −n·d < 0) it returns a negative intensity, and a
point on the projector's plane (it_local.z = 0) gives ±inf.  Mitsuba's integrators call
eval_direction only on samples with ds.pdf != 0 (path.cpp:248-255, prb.py, prb_projective.py,
direct_projective.py), so no render changes; a caller that evaluates a delta emitter's
direction without that mask gets negative light.

Run: python tests/repro/projector_eval_direction_unmasked.py  -> exit 1 while present.
"""
import sys

try:                                   # phonglab pins a libLLVM that Dr.Jit can use
    import phonglab.runtime
    phonglab.runtime.configure()
except ImportError:
    pass
import drjit as dr
import mitsuba as mi

mi.set_variant("llvm_ad_rgb")
projector = mi.load_dict({"type": "projector", "irradiance": 1.0})   # looks along +z
it = dr.zeros(mi.Interaction3f, 1)
it.p = mi.Point3f(0.1, 0.2, -1.0)                                     # behind it
ds, w = projector.sample_direction(it, mi.Point2f(0.5, 0.5))
ev = projector.eval_direction(it, ds)
pdf, w0, e0 = float(ds.pdf[0]), float(w[0][0]), float(ev[0][0])
print(f"behind the projector: ds.pdf = {pdf:g}, weight = {w0:g}, eval_direction = {e0:g}")
present = pdf == 0 and e0 < 0
print("behaviour present: eval_direction is negative where sample_direction returns pdf 0"
      if present else "fixed: eval_direction is not negative outside the frustum")
sys.exit(1 if present else 0)
