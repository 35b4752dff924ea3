"""Mitsuba 3.9.1 pplastic (polarized variants): the diffuse term loses precision at grazing wi.

The unpolarized branch multiplies (1 - R(cos_theta_o)) (1 - R(cos_theta_i)) directly
(src/bsdfs/pplastic.cpp:429-432) and is reciprocal to float32 precision.  The polarized branch
gets the second transmission from the internally refracted direction: line 375 refracts
wi_hat inside and line 376 evaluates mueller::specular_transmission(|cos(wi_hat_p)|, 1/eta) there.  For
grazing wi the internal direction is near the critical angle, where 1 - eta^2 sin^2 cancels
in float32, so the intensity of f(wi, wo) and f(wo, wi) differ by ~1 % at cos = 0.0019, while
the unpolarized variant agrees to 2e-8.

Run: python tests/repro/pplastic_polarized_grazing.py  -> exit 1 while the effect is present.
"""
import sys

try:                                   # phonglab pins a libLLVM that Dr.Jit can use
    import phonglab.runtime
    phonglab.runtime.configure()
except ImportError:
    pass
import drjit as dr
import mitsuba as mi

A = (0.9797958971132713, 0.0, 0.2)
B = (0.9973921455628718, -0.07214896141363494, 0.0018534660571800643)   # grazing


def f(wi, wo, bsdf):
    si = dr.zeros(mi.SurfaceInteraction3f, 1)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    si.wavelengths = mi.UnpolarizedSpectrum(550.0)
    si.wi = dr.normalize(mi.Vector3f(*wi))
    w = dr.normalize(mi.Vector3f(*wo))
    value = bsdf.eval(mi.BSDFContext(), si, w)
    if mi.is_polarized:
        value = mi.unpolarized_spectrum(value)
    return float(value[0][0]) / float(w.z[0])


rel = {}
for variant in ("llvm_ad_spectral", "llvm_ad_spectral_polarized"):
    mi.set_variant(variant)
    bsdf = mi.load_dict({"type": "pplastic"})
    fab, fba = f(A, B, bsdf), f(B, A, bsdf)
    rel[variant] = abs(fab - fba) / fba
    print(f"{variant}: f(a, b) = {fab:.7g}, f(b, a) = {fba:.7g}, relative difference "
          f"{rel[variant]:.2g}")
sys.exit(1 if rel["llvm_ad_spectral_polarized"] > 1e-3 else 0)
