"""Mitsuba 3.9.1 mask: eval_diffuse_reflectance() ignores the opacity that eval() applies.

src/bsdfs/mask.cpp:229-231 returns ``m_nested_bsdf->eval_diffuse_reflectance(si, active)``,
while eval() (line 169 on) returns the nested eval times the opacity.  A mask of opacity 0.5
around diffuse(0.5) reflects a diffuse albedo of 0.25, and Mitsuba's own default
(src/render/bsdf.cpp:38-43, pi * eval(wi, n)) also gives 0.25, but the method reports 0.5:
the aov integrator's albedo (aov.cpp:257) shows a half-transparent surface at full colour.

Run: python tests/repro/mask_diffuse_reflectance_opacity.py  -> exit 1 while the bug is present.
"""
import math
import sys

try:                                   # phonglab pins a libLLVM that Dr.Jit can use
    import phonglab.runtime
    phonglab.runtime.configure()
except ImportError:
    pass
import mitsuba as mi

mi.set_variant("scalar_rgb")
bsdf = mi.load_dict({"type": "mask", "opacity": 0.5, "bsdf": {"type": "diffuse", "reflectance": 0.5}})
si = mi.SurfaceInteraction3f()
si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
si.wi = mi.Vector3f(0.6, 0.0, 0.8)
reported = bsdf.eval_diffuse_reflectance(si)[0]
default = math.pi * bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(0, 0, 1))[0]
print(f"eval_diffuse_reflectance = {reported:.4f}; pi * eval(wi, n) = {default:.4f} "
      f"(the albedo of the masked diffuse lobe, 0.5 * 0.5)")
sys.exit(1 if abs(reported - default) > 1e-4 else 0)
