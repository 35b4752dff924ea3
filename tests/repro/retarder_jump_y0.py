"""Mitsuba 3.9.1 retarder: the Mueller matrix jumps across wi.y = 0 (mitsuba3#1963, open).

sample() re-expresses the element's matrix from the fixed axis (1, 0, 0) into
stokes_basis(forward) with rotate_mueller_basis_collinear (src/bsdfs/retarder.cpp:129-131)
without projecting the axis onto the plane normal to forward (polarizer.cpp:134-136 does).
rotate_stokes_basis signs its angle with dot(forward, cross(x, b)), which changes sign with
forward.y: for an oblique wi the matrix differs on both sides of y = 0 by O(1).

Run: python tests/repro/retarder_jump_y0.py  -> exit 1 while the effect is present.
"""
import sys

try:                                   # phonglab pins a libLLVM that Dr.Jit can use
    import phonglab.runtime
    phonglab.runtime.configure()
except ImportError:
    pass
import drjit as dr
import mitsuba as mi

mi.set_variant("llvm_ad_spectral_polarized")
bsdf = mi.load_dict({"type": "retarder", "theta": 30.0, "delta": 90.0})


def matrix(y):
    si = dr.zeros(mi.SurfaceInteraction3f, 1)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    si.wavelengths = mi.UnpolarizedSpectrum(550.0)
    si.wi = dr.normalize(mi.Vector3f(0.5, y, 0.8))
    _, m = bsdf.sample(mi.BSDFContext(), si, 0.5, mi.Point2f(0.5, 0.5))
    return [[float(m[i][j][0][0]) for j in range(4)] for i in range(4)]


above, below = matrix(1e-5), matrix(-1e-5)
jump = max(abs(a - b) for ra, rb in zip(above, below) for a, b in zip(ra, rb))
print(f"wi = (0.5, +1e-5, 0.8): M1* = {[round(v, 4) for v in above[1]]}")
print(f"wi = (0.5, -1e-5, 0.8): M1* = {[round(v, 4) for v in below[1]]}")
print(f"largest entry difference across wi.y = 0: {jump:.3g} (M00 = 1)")
sys.exit(1 if jump > 1e-2 else 0)
