"""Mitsuba 3.9.1 prbvolpath renders one bounce beyond max_depth on surfaces.

src/python/python/ad/integrators/prbvolpath.py (commit 478e193a): each loop iteration sets
``active_surface = active & ~active_medium`` (line 152) before the depth test
``active &= depth < self.max_depth`` (line 192), which masks ``active`` and the medium events
but not ``active_surface``: a path whose BSDF sample has made depth == max_depth still adds the
emission its ray hits (MIS-weighted, lines 235-247) and samples one more direction; only the
next iteration stops.  In a closed emitting box (albedo 0.5, Le = 2) max_depth 1 must read
Le = 2 (path: 2 exactly); prbvolpath reads 2.65, and 3.34 for 3 at max_depth 2.

Run: python tests/repro/prbvolpath_depth_limit.py  -> exit 1 while the behaviour is present.
"""
import sys

try:                                   # phonglab pins a libLLVM that Dr.Jit can use
    import phonglab.runtime
    phonglab.runtime.configure()
except ImportError:
    pass
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
scene = mi.load_dict({
    "type": "scene",
    "box": {"type": "cube", "flip_normals": True,
            "bsdf": {"type": "diffuse", "reflectance": 0.5},
            "emitter": {"type": "area", "radiance": 2.0}},
    "sensor": {"type": "perspective", "fov": 60,
               "film": {"type": "hdrfilm", "width": 16, "height": 16},
               "sampler": {"type": "independent", "sample_count": 64}}})
out = {}
for name in ("path", "prbvolpath"):
    for depth in (1, 2):
        img = mi.render(scene, integrator=mi.load_dict({"type": name, "max_depth": depth}))
        out[name, depth] = float(np.mean(img))
for depth, exact in ((1, 2.0), (2, 3.0)):
    print(f"max_depth {depth}: exact {exact}, path {out['path', depth]:.4f}, "
          f"prbvolpath {out['prbvolpath', depth]:.4f}")
present = out["prbvolpath", 1] > 2.1 and abs(out["path", 1] - 2.0) < 1e-3
print("behaviour present: prbvolpath adds a bounce beyond max_depth" if present else "fixed")
sys.exit(1 if present else 0)
