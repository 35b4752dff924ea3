"""Mitsuba 3.9.1 mask: sample() with a context restricted to one side samples the OTHER side.

In src/bsdfs/mask.cpp sample(), ``opacity`` is the probability of sampling the nested BSDF
(line 157: nested when sample1 < opacity; the pass-through Null lobe has pdf 1 - opacity,
line 146).  When the context enables only one of the two, line 140 sets
``opacity = sample_transmission ? 1.f : 0.f`` -- inverted: a context without the Null lobe
(only the nested BSDF) gets opacity 0 and returns ONLY pass-through samples (wo = -wi, type
Null), and a context with only the Null lobe samples only the nested BSDF.  pdf() (lines
177-192) does it the right way round (nested pdf, unscaled, when only the nested lobes are on).

Run: python tests/repro/mask_restricted_context.py  -> exit 1 while the bug is present.
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
bsdf = mi.load_dict({"type": "mask", "opacity": 0.5, "bsdf": {"type": "diffuse"}})
n = 10_000
si = dr.zeros(mi.SurfaceInteraction3f, n)
si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
si.wi = mi.Vector3f(0.6, 0.0, 0.8)
ctx = mi.BSDFContext(mi.TransportMode.Radiance, mi.BSDFFlags.DiffuseReflection)  # no Null lobe
rng = np.random.default_rng(1)
bs, weight = bsdf.sample(ctx, si, mi.Float(rng.random(n)),
                         mi.Point2f(rng.random(n), rng.random(n)))
null = (np.array(bs.sampled_type) & int(mi.BSDFFlags.Null)) != 0
print(f"context = DiffuseReflection only: {null.mean():.0%} of the samples are Null "
      f"(pass-through) samples (expected 0%)")
sys.exit(1 if null.any() else 0)
