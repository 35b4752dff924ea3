"""phonglab's whitted (radiance units): area emitters do not light surfaces, by design.

plugins/whitted.py:48: "Area and environment emitters do not light surfaces in this model:
they are seen (L_e) directly or through reflected and transmitted rays".  In a closed
emitting box of albedo 0.5 (Le = 2) path gives Le (1 - rho^D)/(1 - rho) = 3 at max_depth 2;
whitted gives Le = 2.  Where the model is exact (point lights, max_depth 2) it equals path.

Run: python tests/repro/whitted_area_light.py  -> exit 1 while the behaviour is present.
"""
import sys

import phonglab

phonglab.register("llvm_ad_rgb")
import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402

scene = mi.load_dict({
    "type": "scene",
    "box": {"type": "cube", "flip_normals": True,
            "bsdf": {"type": "diffuse", "reflectance": 0.5},
            "emitter": {"type": "area", "radiance": 2.0}},
    "sensor": {"type": "perspective", "fov": 60,
               "film": {"type": "hdrfilm", "width": 8, "height": 8},
               "sampler": {"type": "independent", "sample_count": 64}}})
means = {name: float(np.mean(mi.render(scene, integrator=mi.load_dict(
    {"type": name, "max_depth": 2, **({"units": "radiance"} if name == "whitted" else {})}))))
    for name in ("path", "whitted")}
print(f"enclosure at max_depth 2: path {means['path']:.4f} (exact 3), "
      f"whitted {means['whitted']:.4f}")
present = abs(means["whitted"] - 2.0) < 0.01 and abs(means["path"] - 3.0) < 0.1
print("behaviour present: whitted leaves the area light out of surface lighting" if present
      else "changed")
sys.exit(1 if present else 0)
