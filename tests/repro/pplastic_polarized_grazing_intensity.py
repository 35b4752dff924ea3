"""Mitsuba 3.9.1 pplastic (polarized variants): the intensity is 0 at grazing incidence.

At cos_theta_i = 1e-4 the polarized diffuse term refracts wi_hat inside (src/bsdfs/pplastic.cpp:
375) to the critical angle, where mueller::specular_transmission(|cos|, 1/eta) (line 376)
rounds to 0 in float32: M00 of the polarized eval is 0, while the unpolarized variant (lines
429-431, (1 - R(cos_theta_o)) (1 - R(cos_theta_i)) directly) returns 8.8e-5 at this wo
(550 nm); pplastic/rough-ggx's case (its specular lobe unaffected) is 0.8 % low there.  Away from grazing
(cos_theta_i >= 0.2) the two variants agree to float32 precision.

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


CASES = {"pplastic/default": {"type": "pplastic"},
         "pplastic/rough-ggx": {"type": "pplastic", "alpha": 0.3, "distribution": "ggx",
                                "diffuse_reflectance": {"type": "rgb",
                                                        "value": [0.3, 0.5, 0.2]}}}


def intensity(variant, spec, wi, wo):
    """M00 (the intensity) of eval for each pair of rows of wi and wo, at 550 nm."""
    mi.set_variant(variant)
    bsdf = mi.load_dict(spec)
    n = len(wi)
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    si.wavelengths = mi.UnpolarizedSpectrum(550.0)
    si.wi = mi.Vector3f(*[list(c) for c in zip(*wi)])
    value = bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(*[list(c) for c in zip(*wo)]))
    if mi.is_polarized:
        value = mi.unpolarized_spectrum(value)
    return [float(v) for v in value[0]]


# away from grazing: cos_theta_i 0.2-1 against a few outgoing directions
LATTICE = [((math.sqrt(1 - c * c) * math.cos(p), math.sqrt(1 - c * c) * math.sin(p), c), wo)
           for c in (0.2, 0.4, 0.6, 0.8, 1.0) for p in (0.0, 2.1)
           for wo in (WO, (0.6, 0.0, 0.8), (-0.28, -0.48, math.sqrt(1 - 0.28 ** 2 - 0.48 ** 2)))]
rels = {}
for label, spec in CASES.items():
    u, p = (intensity(v, spec, [WI], [WO])[0]
            for v in ("llvm_ad_spectral", "llvm_ad_spectral_polarized"))
    rels[label] = abs(p - u) / max(abs(u), 1e-30)
    uu, pp = (intensity(v, spec, [a for a, _ in LATTICE], [b for _, b in LATTICE])
              for v in ("llvm_ad_spectral", "llvm_ad_spectral_polarized"))
    away = max(abs(b - a) / max(abs(a), 1e-30) for a, b in zip(uu, pp))
    print(f"{label}: cos_theta_i = 1e-4: unpolarized eval {u:.4g}, polarized M00 {p:.4g}, "
          f"relative difference {rels[label]:.2g}; cos_theta_i >= 0.2 ({len(LATTICE)} lanes): "
          f"largest relative difference {away:.2g}")
sys.exit(1 if rels["pplastic/default"] > 1e-3 else 0)
