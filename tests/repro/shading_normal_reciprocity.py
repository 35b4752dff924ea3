"""Mitsuba 3.9.1 normalmap / bumpmap: not reciprocal w.r.t. the geometric normal (by design).

src/bsdfs/normalmap.cpp:162-175 evaluates the nested BSDF in the perturbed frame and returns
f(wi', wo') cos theta'_o, zeroed where wo and its perturbed image wo' are on different sides
(line 168); src/bsdfs/bumpmap.cpp:168-182 does the same (mask at lines 173-174), in the frame
it builds from the height field's gradient and si.dp_du, si.dp_dv (lines 224-235).  With the geometric cosine taken out,
f(a, b) = eval(a, b) / cos_b differs from f(b, a) = eval(b, a) / cos_a: shading normals are not
reciprocal (E. Veach, "Robust Monte Carlo Methods for Light Transport Simulation", 1997,
sec. 5.3).  Documented as KNOWN in docs/conformance.md, not a bug.

Run: python tests/repro/shading_normal_reciprocity.py  -> exit 1 while the asymmetry is present.
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
n = np.array([0.3, 0.2, 1.0]) / np.linalg.norm([0.3, 0.2, 1.0])
img = np.tile(((n + 1) / 2).astype(np.float32), (4, 4, 1))
normalmap = mi.load_dict({"type": "normalmap", "bsdf": {"type": "diffuse"},
                          "normalmap": {"type": "bitmap", "bitmap": mi.Bitmap(img), "raw": True}})
ramp = np.tile(((np.arange(16) + 0.5) / 16).astype(np.float32)[None, :, None], (16, 1, 1))
bumpmap = mi.load_dict({"type": "bumpmap", "bsdf": {"type": "diffuse"},          # h(u, v) = u
                        "texture": {"type": "bitmap", "bitmap": mi.Bitmap(ramp), "raw": True}})
a = mi.Vector3f(0.6, 0.0, 0.8)
b = mi.Vector3f(-0.28, 0.0, 0.96)


def f(bsdf, wi, wo):
    si = dr.zeros(mi.SurfaceInteraction3f, 1)
    si.n = mi.Normal3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    si.uv = mi.Point2f(0.5, 0.5)
    si.dp_du, si.dp_dv = mi.Vector3f(1, 0, 0), mi.Vector3f(0, 1, 0)    # a unit square
    si.wi = wi
    return float(bsdf.eval(mi.BSDFContext(), si, wo).x[0]) / float(wo.z[0])


asymmetric = True
for name, bsdf in (("normalmap", normalmap), ("bumpmap", bumpmap)):
    fab, fba = f(bsdf, a, b), f(bsdf, b, a)
    print(f"{name}: f(a, b) = {fab:.6f}, f(b, a) = {fba:.6f} (equal for a reciprocal BRDF)")
    asymmetric &= abs(fab - fba) > 1e-4 * max(fab, fba)
sys.exit(1 if asymmetric else 0)
