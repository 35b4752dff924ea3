"""Mitsuba 3.9.1 principledthin: the specular transmission lobe is not reciprocal.

A thin sheet transmits with eta = 1, so f(wi, wo) = f(wo, wi) must hold for transmission too.
src/bsdfs/principledthin.cpp:451-454 builds the half vector from the MIRRORED outgoing
direction wo_r (z -> |z|), but the lobe mask at line 461-463,
``mac_mic_compatibility(wh, wi, wo_t, wi.z(), false)``, tests the unmirrored wo_t against that
half vector: whether the lobe is on depends on which of the two directions is the grazing one.
The value itself (line 522-524, D G (1 - F) / (4 cos_theta_i), i.e. f = D G (1 - F) /
(4 cos_i |cos_o|)) is symmetric.

Run: python tests/repro/principledthin_transmission_reciprocity.py -> exit 1 while present.
"""
import sys

try:                                   # phonglab pins a libLLVM that Dr.Jit can use
    import phonglab.runtime
    phonglab.runtime.configure()
except ImportError:
    pass
import drjit as dr
import mitsuba as mi

mi.set_variant("llvm_ad_rgb")
bsdf = mi.load_dict({"type": "principledthin", "roughness": 0.4, "spec_trans": 0.3})
a = dr.normalize(mi.Vector3f(-0.4946, 0.8458, 0.2))
b = dr.normalize(mi.Vector3f(0.4938, -0.8693, -0.02158))     # transmitted, grazing


def f(wi, wo):
    si = dr.zeros(mi.SurfaceInteraction3f, 1)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    si.wi = wi
    return float(bsdf.eval(mi.BSDFContext(), si, wo).x[0]) / abs(float(wo.z[0]))


fab, fba = f(a, b), f(b, a)
print(f"f(a, b) = {fab:.6g}, f(b, a) = {fba:.6g} (equal for a thin sheet, eta = 1)")
# the defaults with the lobe on (spec_trans 1), a pair that is not grazing
bsdf = mi.load_dict({"type": "principledthin", "spec_trans": 1.0})
c = dr.normalize(mi.Vector3f(-0.40387688, 0.69056749, 0.6))
d = dr.normalize(mi.Vector3f(0.27468443, 0.50496073, -0.81826837))
fcd, fdc = f(c, d), f(d, c)
print(f"spec_trans 1: f(c, d) = {fcd:.6g}, f(d, c) = {fdc:.6g}")
bad = [abs(x - y) > 1e-3 * max(x, y) for x, y in ((fab, fba), (fcd, fdc))]
sys.exit(1 if any(bad) else 0)
