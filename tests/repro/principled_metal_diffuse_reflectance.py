"""Mitsuba 3.9.1 principled: a metal reports base_color as its diffuse reflectance.

src/bsdfs/principled.cpp:841 returns base_color from eval_diffuse_reflectance() without the
diffuse weight brdf = (1 - metallic)(1 - spec_trans) that eval() applies (lines 515, 568).  At
specular 0 the metal is entirely black (eta = 1, line 230, makes F_spec_dielectric 0 and the
specular mask `F_spec_dielectric > 0`, line 555, switches the metallic lobe off), so the
mismatch is plain: eval = 0 everywhere, eval_diffuse_reflectance = 0.5.

Run: python tests/repro/principled_metal_diffuse_reflectance.py -> exit 1 while present.
"""
import sys

import numpy as np

try:                                   # phonglab pins a libLLVM that Dr.Jit can use
    import phonglab.runtime
    phonglab.runtime.configure()
except ImportError:
    pass
import drjit as dr
import mitsuba as mi

mi.set_variant("llvm_ad_rgb")
bsdf = mi.load_dict({"type": "principled", "metallic": 1.0, "roughness": 0.2, "specular": 0.0})
rng = np.random.default_rng(0)
n = 4096
wo = rng.normal(size=(n, 3))
wo[:, 2] = np.abs(wo[:, 2])
wo /= np.linalg.norm(wo, axis=1, keepdims=True)
si = dr.zeros(mi.SurfaceInteraction3f, n)
si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
si.wi = mi.Vector3f(0.6, 0.0, 0.8)
ev = np.array(bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(wo[:, 0], wo[:, 1], wo[:, 2])).x)
edr = float(np.array(bsdf.eval_diffuse_reflectance(si).x)[0])
print(f"metallic 1, specular 0: max eval over {n} directions = {ev.max():.3g}, "
      f"eval_diffuse_reflectance = {edr:.3g} (expected the diffuse albedo, 0)")
sys.exit(1 if edr > 1e-3 and ev.max() == 0 else 0)
