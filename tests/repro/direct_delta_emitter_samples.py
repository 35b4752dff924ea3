"""Mitsuba 3.9.1 `direct` sums its emitter samples of a delta light instead of averaging them.

src/integrators/direct.cpp:180-181 (tag v3.9.1): the emitter strategy's weight is
`dr::select(ds.delta, 1.f, mis_weight(...) * m_weight_lum)`, so the 1/emitter_samples factor
(m_weight_lum, line 109) applies to area lights only; a point, spot or directional light adds
its full contribution once per emitter sample.  With emitter_samples = N the image of a plane
lit by a point light is N times the exact one (mitsuba3 issue #1861, fix proposed in
PR #1863, open).

Run: python tests/repro/direct_delta_emitter_samples.py  -> exit 1 while the behaviour is present.
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
mean = {n: float(np.mean(mi.render(scene, integrator=mi.load_dict(
    {"type": "direct", "emitter_samples": n})))) for n in (1, 4)}
ratio = mean[4] / mean[1]
print(f"image mean: emitter_samples 1 -> {mean[1]:.4f}, 4 -> {mean[4]:.4f} (ratio {ratio:.3f})")
present = abs(ratio - 4.0) < 0.05
print("behaviour present: 4 emitter samples of a point light are summed" if present
      else "changed: the emitter samples of a point light are averaged")
sys.exit(1 if present else 0)
