"""Mitsuba 3.9.1 blendbsdf: samples of bsdf_1 keep bsdf_1's own component index.

src/bsdfs/blendbsdf.cpp:94-97 numbers the components of the blend bsdf_0's first, then
bsdf_1's (offset by bsdf_0->component_count()), and eval/pdf with ctx.component subtract that
offset (lines 116-120, 167-171).  But sample() copies bs1 as is (line 154, also line 123 in
the restricted-context branch), so a sample from bsdf_1 reports bsdf_1's LOCAL index: blending
diffuse (component 0) with roughconductor (its component 0 = blend component 1) reports
component 0 with type GlossyReflection, which flags(0) = DiffuseReflection does not contain.

Run: python tests/repro/blendbsdf_component_ids.py  -> exit 1 while the bug is present.
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
bsdf = mi.load_dict({"type": "blendbsdf", "weight": 0.3, "bsdf_0": {"type": "diffuse"},
                     "bsdf_1": {"type": "roughconductor", "alpha": 0.2}})
n = 10_000
si = dr.zeros(mi.SurfaceInteraction3f, n)
si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
si.wi = mi.Vector3f(0.6, 0.0, 0.8)
rng = np.random.default_rng(1)
bs, weight = bsdf.sample(mi.BSDFContext(), si, mi.Float(rng.random(n)),
                         mi.Point2f(rng.random(n), rng.random(n)))
comp = np.array(bs.sampled_component)
stype = np.array(bs.sampled_type)
glossy = (stype & int(mi.BSDFFlags.GlossyReflection)) != 0
print(f"components: {[int(bsdf.flags(i)) for i in range(bsdf.component_count())]}; "
      f"glossy samples report components {sorted(set(comp[glossy].tolist()))} (expected [1])")
sys.exit(1 if np.any(comp[glossy] != 1) else 0)
