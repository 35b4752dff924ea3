"""Mitsuba 3.9.1 heterogeneous: the majorant leaves out a microflake phase function's
projected area, so σ_n < 0 where that area exceeds 1.

src/media/heterogeneous.cpp (commit 478e193a) line 163: ``m_max_density = m_scale *
m_sigmat->max()``, returned by ``get_majorant`` (181); ``get_scattering_coefficients`` multiplies
σ_t by the phase function's ``projected_area`` (190-191) and returns σ_n = m_max_density − σ_t
(194).  SGGX's projected area is sqrt(wiᵀ S wi) (include/mitsuba/render/microflake.h:154-163),
above 1 for any S with an eigenvalue above 1 (sggx.cpp asks only for a positive definite S):
then σ_t > majorant, σ_n < 0, and volpath's null-collision probability mean(σ_n/σ̄)
(volpath.cpp:238) is negative: every collision is taken as real at the majorant's rate, too
few.

Run: python tests/repro/heterogeneous_microflake_majorant.py  -> exit 1 while the behaviour is
present.
"""
import sys

try:                                   # phonglab pins a libLLVM that Dr.Jit can use
    import phonglab.runtime
    phonglab.runtime.configure()
except ImportError:
    pass
import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
S = mi.TensorXf(np.array([1.0, 1.0, 4.0, 0.0, 0.0, 0.0], np.float32), (1, 1, 1, 6))
medium = mi.load_dict({"type": "heterogeneous",
                       "sigma_t": {"type": "gridvolume",
                                   "grid": mi.VolumeGrid(np.full((2, 2, 2, 1), 2.0, np.float32))},
                       "phase": {"type": "sggx", "S": {"type": "gridvolume", "data": S}}})
mei = dr.zeros(mi.MediumInteraction3f, 1)
mei.wi = mi.Vector3f(0.0, 0.0, 1.0)          # along S's largest eigenvector: area 2
mei.sh_frame = mi.Frame3f(mei.wi)
majorant = float(np.array(medium.get_majorant(mei, mi.Bool(True)))[0, 0])
mei.p = mi.Point3f(0.5, 0.5, 0.5)
sigma_s, sigma_n, sigma_t = medium.get_scattering_coefficients(mei, mi.Bool(True))
sn, st = float(np.array(sigma_n)[0, 0]), float(np.array(sigma_t)[0, 0])
print(f"majorant {majorant}, sigma_t {st}, sigma_n {sn} at the centre, wi = +z")
sys.exit(1 if sn < 0 else 0)
