"""Mitsuba 3.9.1 roughplastic with both reflectances 0: a NaN pdf for every direction.

src/bsdfs/roughplastic.cpp:229 sets ``m_specular_sampling_weight = s_mean / (d_mean + s_mean)``
from the means of specular_reflectance and diffuse_reflectance; with both 0 that is 0/0 = NaN,
so prob_specular and prob_diffuse (lines 279-280, 400-401, 446-447) are NaN and pdf() and
eval_pdf() return NaN for every direction (eval() is a correct 0).  Mitsuba's own path
tracer is unaffected: its MIS weight drops a non-finite value (src/integrators/path.cpp:363,
``dr::select(dr::isfinite(w), w, 0.f)``), so the render below has no NaN pixel; an integrator
or a plugin that uses the pdf directly (a custom MIS, a guiding density) gets NaN.  A black
material is a legitimate input (reflectance textures that reach 0, an optimization driving
them to 0).

Run: python tests/repro/roughplastic_black_nan.py  -> exit 1 while the bug is present.
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
import numpy as np

mi.set_variant("llvm_ad_rgb")
black = {"type": "roughplastic", "diffuse_reflectance": 0.0, "specular_reflectance": 0.0}
bsdf = mi.load_dict(black)
si = dr.zeros(mi.SurfaceInteraction3f, 1)
si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
t = math.radians(40)
si.wi = mi.Vector3f(math.sin(t), 0, math.cos(t))
wo = mi.Vector3f(-0.3, 0.1, math.sqrt(1 - 0.1))
pdf = float(bsdf.pdf(mi.BSDFContext(), si, wo)[0])
value = float(bsdf.eval(mi.BSDFContext(), si, wo).x[0])
print(f"black roughplastic: eval = {value}, pdf = {pdf} (expected a finite pdf)")
scene = mi.load_dict({
    "type": "scene", "integrator": {"type": "path", "max_depth": 3},
    "sensor": {"type": "perspective", "fov": 40,
               "to_world": mi.ScalarTransform4f().look_at([0, 0, 3], [0, 0, 0], [0, 1, 0]),
               "film": {"type": "hdrfilm", "width": 16, "height": 16},
               "sampler": {"type": "independent", "sample_count": 4}},
    "floor": {"type": "rectangle", "bsdf": black},
    "light": {"type": "rectangle", "emitter": {"type": "area", "radiance": 1.0},
              "to_world": mi.ScalarTransform4f().translate([0, 0, 2]).rotate([1, 0, 0], 180)
              .scale(0.5)}})
image = np.array(mi.render(scene, seed=0))
nan = int(np.isnan(image).any(axis=2).sum())
print(f"path tracer, 16x16 pixels of the black floor: {nan} NaN pixels (its MIS weight "
      f"drops the NaN)")
sys.exit(1 if math.isnan(pdf) else 0)
