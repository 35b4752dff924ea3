"""Mitsuba 3.9.1 roughplastic with specular_reflectance 0: pdf() is NaN below the horizon.

With specular_reflectance = 0, m_specular_sampling_weight is 0 (roughplastic.cpp:229).  On a
lane that pdf() masks off (cos θ_o ≤ 0, line 391), lerp_gather (lines 396-397) returns
t_i = 0 under the inactive mask, so prob_specular = (1 − 0)·0 and prob_diffuse = 0·1
(lines 400-401), and prob_specular / (prob_specular + prob_diffuse) (line 406) is 0/0.
pdf() returns `result` without masking it (line 422; eval_pdf() likewise at line 501), so the
caller gets NaN for wo below the horizon, at any int_ior.  With specular_reflectance > 0 the
same lanes get a finite but wrong density instead (tests/repro/roughplastic_pdf_below_horizon.py).
Mitsuba's path tracer never asks for such a pdf; an integrator or MIS scheme that evaluates
pdf() for a direction below the horizon (a light sample behind the surface) gets NaN.

Run: python tests/repro/roughplastic_pdf_nan_specular0.py  -> exit 1 while the bug is present.
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
bsdf = mi.load_dict({"type": "roughplastic", "distribution": "ggx", "alpha": 0.5,
                     "diffuse_reflectance": 0.5, "specular_reflectance": 0.0})
si = dr.zeros(mi.SurfaceInteraction3f, 2)
si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
t = math.radians(45)
si.wi = mi.Vector3f(math.sin(t), 0, math.cos(t))
wo = mi.Vector3f(mi.Float([-0.6, -0.6]), 0, mi.Float([0.8, -0.8]))    # above, below
pdf = np.array(bsdf.pdf(mi.BSDFContext(), si, wo))
value = np.array(bsdf.eval(mi.BSDFContext(), si, wo).x)
print(f"roughplastic, specular_reflectance 0, wi at 45 deg: pdf above the horizon {pdf[0]:.4f}, "
      f"below {pdf[1]} (eval below: {value[1]}; expected pdf 0 below)")
sys.exit(1 if not np.isfinite(pdf[1]) else 0)
