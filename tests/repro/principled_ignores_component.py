"""Mitsuba 3.9.1 principled / principledthin: a context restricted to one component, or to
some lobe types (ctx.type_mask), is ignored.

Neither src/bsdfs/principled.cpp nor src/bsdfs/principledthin.cpp calls ctx.is_enabled() or
reads ctx.component: the lobe probabilities of sample() (principled.cpp:377-393,
principledthin.cpp:291-299) and the lobes summed by eval()/pdf() are the same for every
context, so BSDFContext(component=k) or BSDFContext(type_mask=DiffuseReflection) still
samples and evaluates all lobes (other plugins,
e.g. roughplastic.cpp:264-265, restrict themselves with ctx.is_enabled(flag, index)).

Run: python tests/repro/principled_ignores_component.py  -> exit 1 while the bug is present.
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
n = 10_000
si = dr.zeros(mi.SurfaceInteraction3f, n)
si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
si.wi = mi.Vector3f(0.6, 0.0, 0.8)
rng = np.random.default_rng(1)
u1, u2 = mi.Float(rng.random(n)), mi.Point2f(rng.random(n), rng.random(n))
bad = False
SPECS = {"principled": {"type": "principled", "spec_trans": 0.4, "clearcoat": 0.5},
         "principledthin": {"type": "principledthin", "spec_trans": 0.3, "diff_trans": 0.4}}
for plugin, spec in SPECS.items():
    bsdf = mi.load_dict(spec)
    ctx = mi.BSDFContext(mi.TransportMode.Radiance, mi.BSDFFlags.All, 0)   # component 0 only
    bs, weight = bsdf.sample(ctx, si, u1, u2)
    ids = sorted(set(np.array(bs.sampled_component)[np.array(bs.pdf) > 0].tolist()))
    print(f"{plugin}: context component 0 -> sampled components {ids} (expected [0])")
    bad |= ids != [0]
    ctx = mi.BSDFContext(mi.TransportMode.Radiance, mi.BSDFFlags.DiffuseReflection)
    bs, weight = bsdf.sample(ctx, si, u1, u2)
    live = np.array(bs.pdf) > 0
    types = sorted(set(np.array(bs.sampled_type)[live].tolist()))
    print(f"{plugin}: context type_mask DiffuseReflection (0x2) -> sampled types "
          f"{[hex(t) for t in types]} (expected ['0x2'])")
    bad |= types != [int(mi.BSDFFlags.DiffuseReflection)]
sys.exit(1 if bad else 0)
