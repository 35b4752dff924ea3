"""Mitsuba 3.9.1 principledthin: pdf() is NaN at exactly grazing incidence in vectorized variants.

src/bsdfs/principledthin.cpp:606 sets ``active &= cos_theta_i != 0`` but pdf() ends with an
unmasked ``return pdf;`` (line 704); the early return (line 608) only fires when EVERY lane is
inactive.  A lane with cos_theta_i = 0 in a call with valid lanes therefore returns the NaN of
the microfacet densities (which divide by cos_theta_i) instead of 0 -- the same pattern as
roughplastic.cpp:422.

Run: python tests/repro/principledthin_pdf_nan_grazing.py  -> exit 1 while the bug is present.
"""
import math
import sys

try:                                   # phonglab pins a libLLVM that Dr.Jit can use
    import phonglab.runtime
    phonglab.runtime.configure()
except ImportError:
    pass
import mitsuba as mi

mi.set_variant("llvm_ad_rgb")
bsdf = mi.load_dict({"type": "principledthin", "roughness": 0.4, "spec_trans": 0.3,
                     "diff_trans": 0.4})
si = mi.SurfaceInteraction3f()
si.wi = mi.Vector3f([1.0, 0.6], [0, 0], [0.0, 0.8])          # lane 0 exactly grazing
si.sh_frame = mi.Frame3f(mi.Vector3f([0, 0], [0, 0], [1, 1]))
wo = mi.Vector3f([0.48, 0.48], [0.45, 0.45], [0.75, 0.75])
p = bsdf.pdf(mi.BSDFContext(), si, wo)
print(f"pdf at cos_theta_i = 0: {p[0]} (expected 0); at cos_theta_i = 0.8: {p[1]:.4g}")
sys.exit(1 if math.isnan(p[0]) else 0)
