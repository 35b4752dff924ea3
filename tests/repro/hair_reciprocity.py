"""Mitsuba 3.9.1 hair: f(wi, wo) != f(wo, wi) (by design: a near-field model at one offset h).

src/bsdfs/hair.cpp:348-349 derives the fiber offset h = sin(gamma_i) from wi alone (where the
ray hit the fiber's cross-section); the attenuation and azimuthal terms depend on h, so
swapping wi and wo changes the value.  Documented as KNOWN in docs/conformance.md, not a bug.

Run: python tests/repro/hair_reciprocity.py  -> exit 1 while the asymmetry is present.
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
bsdf = mi.load_dict({"type": "hair"})
a = mi.Vector3f(0.6, 0.3, 0.742)
b = mi.Vector3f(-0.5, 0.2, 0.843)


def f(wi, wo):
    si = dr.zeros(mi.SurfaceInteraction3f, 1)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    si.wi = dr.normalize(wi)
    return float(bsdf.eval(mi.BSDFContext(), si, dr.normalize(wo)).x[0])


fab, fba = f(a, b), f(b, a)
print(f"f(a, b) = {fab:.6g}, f(b, a) = {fba:.6g} (equal for a reciprocal BSDF)")
sys.exit(1 if abs(fab - fba) > 1e-4 * max(fab, fba) else 0)
