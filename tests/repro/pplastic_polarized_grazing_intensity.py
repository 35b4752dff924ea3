"""Mitsuba 3.9.1 pplastic (polarized variants): the intensity is 0 at grazing incidence.

At cos_theta_i = 1e-4 the polarized diffuse term refracts wi_hat inside (src/bsdfs/pplastic.cpp:
375) to the critical angle, where mueller::specular_transmission(|cos|, 1/eta) (line 376)
rounds to 0 in float32: M00 of the polarized eval is 0, while the unpolarized variant (lines
429-432, (1 - R(cos_theta_o)) (1 - R(cos_theta_i)) directly) returns 8.8e-5 at this wo
(550 nm).  Away from grazing
the two variants agree to 2.4e-7.

Run: python tests/repro/pplastic_polarized_grazing_intensity.py  -> exit 1 while the effect is
present.
"""
import math
import sys

try:                                   # phonglab pins a libLLVM that Dr.Jit can use
    import phonglab.runtime
    phonglab.runtime.configure()
except ImportError:
    pass
import drjit as dr
import mitsuba as mi

WI = (math.sqrt(1 - 1e-8), 0.0, 1e-4)        # cos_theta_i = 1e-4
WO = (-0.135059, 0.125851, 0.982813)


def intensity(variant):
    mi.set_variant(variant)
    bsdf = mi.load_dict({"type": "pplastic"})
    si = dr.zeros(mi.SurfaceInteraction3f, 1)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    si.wavelengths = mi.UnpolarizedSpectrum(550.0)
    si.wi = mi.Vector3f(*WI)
    value = bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(*WO))
    if mi.is_polarized:
        value = mi.unpolarized_spectrum(value)
    return float(value[0][0])


unpolarized = intensity("llvm_ad_spectral")
polarized = intensity("llvm_ad_spectral_polarized")
rel = abs(polarized - unpolarized) / max(abs(unpolarized), 1e-30)
print(f"cos_theta_i = 1e-4: unpolarized eval {unpolarized:.7g}, polarized M00 {polarized:.7g}, "
      f"relative difference {rel:.2g}")
sys.exit(1 if rel > 1e-3 else 0)
