"""Mitsuba 3.9.1 pplastic: one component declared, two component indices used.

src/bsdfs/pplastic.cpp:210 declares a single component (flags Glossy|Diffuse), but sample()
reports sampled_component 0 for the specular lobe (line 278) and 1 for the diffuse lobe
(line 284), and eval/pdf/sample enable the lobes with ctx.is_enabled(..., 0) and
ctx.is_enabled(..., 1) (lines 251-252): component 1 does not exist (component_count() == 1).

Run: python tests/repro/pplastic_component_ids.py  -> exit 1 while the bug is present.
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

mi.set_variant("llvm_ad_spectral_polarized")
bsdf = mi.load_dict({"type": "pplastic"})
n = 10_000
si = dr.zeros(mi.SurfaceInteraction3f, n)
si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
si.wi = mi.Vector3f(0.6, 0.0, 0.8)
si.wavelengths = mi.UnpolarizedSpectrum(500.0, 550.0, 600.0, 650.0)
rng = np.random.default_rng(1)
bs, weight = bsdf.sample(mi.BSDFContext(), si, mi.Float(rng.random(n)),
                         mi.Point2f(rng.random(n), rng.random(n)))
ids = sorted(set(np.array(bs.sampled_component).tolist()))
count = bsdf.component_count()
print(f"component_count() = {count}, sampled_component values = {ids}")
sys.exit(1 if max(ids) >= count else 0)
