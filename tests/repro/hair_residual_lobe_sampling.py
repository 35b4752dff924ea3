"""Mitsuba 3.9.1 hair: sample() draws the residual lobe p = P_MAX in the wrong longitudinal direction.

src/bsdfs/hair.cpp:265-271 picks the scale-tilted incident angle per sampled segment count p
with ``for (size_t j = 0; j < P_MAX; j++)`` -- p == P_MAX (= 3, line 526) is never visited, so
for the residual lobe sin_theta_ip = cos_theta_ip = 0 (their initial values, line 265-266) and
line 287-288 gives sin_theta_o = -cos_theta * 0 + sin_theta * cos_phi * 0 = 0: every such
sample lies exactly in the fiber's normal plane (wo.y == 0).  pdf() (line 437) and eval()
(line 389) describe that lobe around -sin_theta_i instead (reframe_with_scales' default case,
which pbrt-v3's hair sampler uses for p >= 3).  mi.chi2 rejects hair at 70 degrees and beyond,
where grazing fiber incidence (|h| -> 1) raises the Fresnel term and with it the residual lobe.

A continuous density gives P(wo.y == 0 exactly) ~ 1e-7 in float32.
Run: python tests/repro/hair_residual_lobe_sampling.py  -> exit 1 while the bug is present.
"""
import math
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
bsdf = mi.load_dict({"type": "hair", "eumelanin": 0.3, "pheomelanin": 0.2})
n = 200_000
theta, phi = math.radians(85), 0.3
si = dr.zeros(mi.SurfaceInteraction3f, n)
si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
si.wi = mi.Vector3f(math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi),
                    math.cos(theta))
rng = np.random.default_rng(3)
bs, weight = bsdf.sample(mi.BSDFContext(), si, mi.Float(rng.random(n)),
                         mi.Point2f(rng.random(n), rng.random(n)))
frac = float(np.mean(np.array(bs.wo.y) == 0.0))
print(f"fraction of samples with wo.y == 0 exactly: {frac:.4f} (expected ~0)")
sys.exit(1 if frac > 1e-4 else 0)
