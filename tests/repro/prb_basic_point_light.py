"""Mitsuba 3.9.1 prb_basic has no emitter sampling: a scene lit by a point light renders black.

src/python/python/ad/integrators/prb_basic.py:28 (commit 478e193a): "Basic Path Replay
Backpropagation-style integrator *without* next event estimation" -- light is collected only
where a BSDF-sampled ray hits an emitter, which a delta light never is.  By design; the
conformance table's plane under a point light (exact value 0.4249) reads 0.

Run: python tests/repro/prb_basic_point_light.py  -> exit 1 while the behaviour is present.
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
    "plane": {"type": "rectangle", "bsdf": {"type": "diffuse", "reflectance": 0.5}},
    "light": {"type": "point", "position": [0.0, 0.0, 1.0], "intensity": 4.0},
    "sensor": {"type": "perspective", "fov": 40,
               "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 3], target=[0, 0, 0],
                                                          up=[0, 1, 0]),
               "film": {"type": "hdrfilm", "width": 16, "height": 16},
               "sampler": {"type": "independent", "sample_count": 16}}})
means = {name: float(np.mean(mi.render(scene, integrator=mi.load_dict({"type": name}))))
         for name in ("path", "prb_basic")}
print(f"image mean: path {means['path']:.4f}, prb_basic {means['prb_basic']:.4f}")
present = means["path"] > 0.01 and means["prb_basic"] == 0.0
print("behaviour present: prb_basic is black under a point light" if present
      else "changed: prb_basic sees the point light")
sys.exit(1 if present else 0)
