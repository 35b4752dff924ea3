"""Mitsuba 3.9.1 dielectric, polarized variants: at grazing incidence a transmitted sample's weight
M00 is not the unpolarized weight.

src/bsdfs/dielectric.cpp:305 evaluates mueller::specular_transmission at the refracted direction
(cos_theta_o_hat) and line 308 divides it by bs.pdf, the transmission probability t_i computed
from the incident side (line 266).  For grazing wi the refracted direction lies at the critical
angle, where cos = sqrt(1 - eta^2 sin^2) cancels in float32, so M00 / t_i is far from the
unpolarized weight 1/eta^2 (t_i / t_i, radiance scaled): 1.79 against 0.444 at cos_theta_i = 1e-4.

Run: python tests/repro/dielectric_polarized_grazing.py  -> exit 1 while the bug is present.
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


def transmitted_weights(variant: str) -> float:
    mi.set_variant(variant)
    bsdf = mi.load_dict({"type": "dielectric", "int_ior": 1.5})
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    si.wi = mi.Vector3f(float(np.sqrt(1 - 1e-8)), 0.0, 1e-4)     # grazing incidence
    si.wavelengths = mi.Float(550.0) if mi.is_spectral else si.wavelengths
    bs, weight = bsdf.sample(mi.BSDFContext(), si, 0.999999, mi.Point2f(0.5, 0.5))
    assert bs.wo.z[0] < 0, "expected the transmitted sample"
    w = np.array(mi.unpolarized_spectrum(weight) if mi.is_polarized else weight)
    return float(np.ravel(w)[0])


polarized = transmitted_weights("llvm_ad_spectral_polarized")
plain = transmitted_weights("llvm_ad_spectral")
print(f"transmitted weight at cos_theta_i = 1e-4: polarized M00 {polarized:.4g}, "
      f"unpolarized {plain:.4g} (1/eta^2 = {1 / 1.5 ** 2:.4g})")
sys.exit(1 if abs(polarized - plain) > 1e-3 * abs(plain) else 0)
