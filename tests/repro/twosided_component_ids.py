"""Mitsuba 3.9.1 twosided with two different BSDFs: samples from the back keep bsdf_1's own
component index.

src/bsdfs/twosided.cpp (tag v3.9.1) numbers the components bsdf_0's first (FrontSide), then
bsdf_1's (BackSide, offset by bsdf_0->component_count(): the constructor's two loops, lines
90-100), and a restricted context on the back side subtracts that offset (lines 137-138).  But
sample() returns bsdf_1's sample as is (`m_brdf[1]->sample(ctx, si, ...)` for the back_side
lanes, lines 141-142), so a
sample for ω_i below the surface reports bsdf_1's LOCAL index: diffuse in front (component 0)
and roughconductor behind (blend component 1) reports component 0 with type GlossyReflection,
which flags(0) = DiffuseReflection | FrontSide does not contain.  (A context restricted to
component 0 also wraps to (uint32_t) -1, every component, on the back side (eval() at
lines 171-172):
Σ_k eval_k is twice eval there.)  Only ω_i below
the surface shows it, which phonglab's identity topics draw.

Run: python tests/repro/twosided_component_ids.py  -> exit 1 while the bug is present.
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
bsdf = mi.load_dict({"type": "twosided", "bsdf_0": {"type": "diffuse"},
                     "bsdf_1": {"type": "roughconductor", "alpha": 0.2}})
n = 10_000
si = dr.zeros(mi.SurfaceInteraction3f, n)
si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
si.wi = mi.Vector3f(np.full(n, 0.6), np.zeros(n), np.full(n, -0.8))   # below: the back BSDF
rng = np.random.default_rng(1)
bs, weight = bsdf.sample(mi.BSDFContext(), si, mi.Float(rng.random(n)),
                         mi.Point2f(rng.random(n), rng.random(n)))
comp = np.array(bs.sampled_component)
stype = np.array(bs.sampled_type)
glossy = (stype & int(mi.BSDFFlags.GlossyReflection)) != 0
print(f"components: {[int(bsdf.flags(i)) for i in range(bsdf.component_count())]}; "
      f"{int(glossy.sum())} glossy samples report components "
      f"{sorted(set(comp[glossy].tolist()))} (expected [1])")
ids_wrong = not glossy.any() or np.any(comp[glossy] != 1)

# the restricted context: line 139 subtracts component_count() on the back side, so k = 0
# wraps to (uint32_t) -1 (every component): Σ_k eval_k = 2 eval below the surface
wo = mi.Vector3f(np.full(n, -0.3), np.full(n, 0.1), np.full(n, -0.9))
wo = dr.normalize(wo)
full = np.array(bsdf.eval(mi.BSDFContext(), si, wo))
parts = 0.0
for k in range(bsdf.component_count()):
    ctx = mi.BSDFContext()
    ctx.component = k
    parts = parts + np.array(bsdf.eval(ctx, si, wo))
ratio = float(np.sum(parts) / np.sum(full))
print(f"Σ_k eval_k / eval below the surface = {ratio:.4f} (expected 1)")
sys.exit(1 if ids_wrong or abs(ratio - 1.0) > 1e-4 else 0)
