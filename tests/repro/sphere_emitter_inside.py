"""Mitsuba 3.9.1 sphere emitter: sample_direction and pdf_direction decide "inside" differently.

src/shapes/sphere.cpp (commit 478e193a): sample_direction samples by area (pdf = dist²/(A|cos|))
when |p − c|² ≤ (r(1 + RayEpsilon))² (flip_normals; lines 256-259), pdf_direction returns the
cone pdf 1/(2π(1 − cos θ_max)) unless r/|p − c| ≥ 1 − 2⁻²⁴ (lines 330-336).  Reference points
on the sphere as a ray from its centre hits it (float32) fall between the two thresholds for
a share of them: there ds.pdf ≠ pdf_direction(ds), which biases MIS next-event estimation
with a camera inside an emitting sphere by about +0.25 % of Le per bounce (docs/checks.md).

Run: python tests/repro/sphere_emitter_inside.py  -> exit 1 while the behaviour is present.
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
shape = mi.load_dict({"type": "sphere", "flip_normals": True,
                      "emitter": {"type": "area", "radiance": 1.0}})
emitter = shape.emitter()
rng = np.random.default_rng(1)
n = 1 << 14
d = rng.normal(size=(n, 3))
d /= np.linalg.norm(d, axis=1, keepdims=True)
si = shape.ray_intersect(mi.Ray3f(mi.Point3f(0.0, 0.0, 0.0),
                                  mi.Vector3f(*(mi.Float(d[:, k]) for k in range(3)))))
it = dr.zeros(mi.Interaction3f, n)
it.p = si.p
u = rng.random((n, 2))
ds, w = emitter.sample_direction(it, mi.Point2f(mi.Float(u[:, 0]), mi.Float(u[:, 1])))
a, b = np.array(ds.pdf), np.array(emitter.pdf_direction(it, ds))
live = np.array(dr.any(w != 0)) & (a > 0)
bad = live & (np.abs(a - b) > 1e-3 * np.abs(a))
print(f"{bad.sum()} of {live.sum()} points on the sphere: ds.pdf != pdf_direction(ds) "
      f"({100 * bad.mean():.1f} %), e.g. ds.pdf = {a[bad][0] if bad.any() else 0:.6g}, "
      f"pdf_direction = {b[bad][0] if bad.any() else 0:.6g}")
sys.exit(1 if bad.any() else 0)
