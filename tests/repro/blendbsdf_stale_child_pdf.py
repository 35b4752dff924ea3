"""Mitsuba 3.9.1 blendbsdf: a sample of bsdf_0 that bsdf_0 itself rejected still carries its pdf.

src/bsdfs/blendbsdf.cpp:138 mixes ``bs0.pdf`` into ``pdf_weighted = weight * pdf1 + (1 - weight)
* bs0.pdf`` (and line 139 ``result0 * bs0.pdf`` into the weight) without asking whether bsdf_0's
sample is valid.  roughconductor sampled from below its surface returns a zero weight but a
non-zero ``bs.pdf`` on some lanes (27 of 1000 at wi.z = -0.7), so the blend of roughconductor
and roughdielectric reports, for those lanes, a ``bs.pdf`` that ``pdf(bs.wo)`` does not give and
a weight that is not eval/pdf.  Above the surface the two agree.

Run: python tests/repro/blendbsdf_stale_child_pdf.py  -> exit 1 while the bug is present.
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
bsdf = mi.load_dict({"type": "blendbsdf", "weight": 0.6,
                     "bsdf_0": {"type": "roughconductor", "alpha": 0.3},
                     "bsdf_1": {"type": "roughdielectric", "alpha": 0.2}})
n = 20_000
r = np.random.default_rng(0)
si = dr.zeros(mi.SurfaceInteraction3f, n)
si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
si.wi = mi.Vector3f(0.714142842854285, 0.0, -0.7)          # below the surface
ctx = mi.BSDFContext()
bs, weight = bsdf.sample(ctx, si, mi.Float(r.random(n)), mi.Point2f(r.random(n), r.random(n)))
pdf = np.array(bsdf.pdf(ctx, si, bs.wo))
bs_pdf = np.array(bs.pdf)
valid = bs_pdf > 0
bad = valid & (np.abs(bs_pdf - pdf) > 0.01 * bs_pdf)
print(f"{int(bad.sum())} of {int(valid.sum())} samples from below: bs.pdf != pdf(bs.wo) by > 1 %"
      + (f" (e.g. {bs_pdf[bad][0]:.4g} against {pdf[bad][0]:.4g})" if bad.any() else ""))
sys.exit(1 if bad.any() else 0)
