"""Mitsuba 3.9.1 principled: sampled_component indices do not match m_components.

src/bsdfs/principled.cpp:241-265 pushes a component only for the lobes that are on (diffuse,
then clearcoat if any, spec_trans if any, then the main specular), so with the defaults
(no clearcoat, no spec_trans) there are 2 components.  sample() hard-codes the indices of the
all-lobes layout: 3 for the main specular (line 423), 2 for spec_trans (line 440), 1 for
clearcoat (line 463).  A default principled reports component 3 of a 2-component BSDF.
(principled also never reads ctx.component, so a context restricted to one component still
samples and evaluates every lobe.)

Run: python tests/repro/principled_component_ids.py  -> exit 1 while the bug is present.
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
bsdf = mi.load_dict({"type": "principled"})
n = 10_000
si = dr.zeros(mi.SurfaceInteraction3f, n)
si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
si.wi = mi.Vector3f(0.6, 0.0, 0.8)
rng = np.random.default_rng(1)
bs, weight = bsdf.sample(mi.BSDFContext(), si, mi.Float(rng.random(n)),
                         mi.Point2f(rng.random(n), rng.random(n)))
ids = sorted(set(np.array(bs.sampled_component).tolist()))
count = bsdf.component_count()
print(f"component_count() = {count}, sampled_component values = {ids}")
# spec_trans on, clearcoat off: m_components = [diffuse, spec_trans, specular], but the
# transmission samples report index 2 (principled.cpp:440), the specular component.
thru = mi.load_dict({"type": "principled", "spec_trans": 1.0})
bs2, _ = thru.sample(mi.BSDFContext(), si, mi.Float(rng.random(n)),
                     mi.Point2f(rng.random(n), rng.random(n)))
comp2, type2 = np.array(bs2.sampled_component), np.array(bs2.sampled_type)
trans = (type2 & int(mi.BSDFFlags.GlossyTransmission)) != 0
shifted = sorted(set(comp2[trans].tolist()))
print(f"spec_trans 1: transmission samples report components {shifted}; "
      f"flags(2) has GlossyReflection: {bool(thru.flags(2) & mi.BSDFFlags.GlossyReflection)}")
sys.exit(1 if max(ids) >= count or 2 in shifted else 0)
