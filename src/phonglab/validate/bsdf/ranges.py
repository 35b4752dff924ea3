r"""The parameters of a BSDF that a sweep varies, and the range of each: which parameters, the
order of precedence of their ranges (declared, documented, probed) and the edges are
:mod:`phonglab.validate.ranges`'; this module holds the BSDF kind's documented table.

:data:`BUILTIN`: Mitsuba 3.9.1's documented ranges of its built-ins, from the plugin reference:
reflectances in [0, 1], microfacet roughness α, where the docs give 0.001-0.01 as "very smooth"
to 0.3+ as "rough", IORs between equal (1) and the densest tabulated materials (≈ 2.4 for
diamond; 3 here), a conductor's η ∈ [0, 5] and k ∈ [0.01, 10] (η = k = 0 is no material);
``alpha`` is held ≥ 0.01, the smoothest lobe the χ² bins resolve.  A built-in whose load-time
names differ from the traversed ones (roughplastic's ``int_ior`` is traversed as ``eta``) is
swept by the load-time names of this table.  A point a plugin refuses at load (k_d + k_s > 1 for
phong at "all at maximum") is reported as outside the plugin's range, not run.
"""

from __future__ import annotations

import mitsuba as mi

from ..ranges import Range, domain as _domain, parameters as _parameters, traversed

__all__ = ["BUILTIN", "NAMED", "Range", "domain", "parameters", "traversed"]

#: Mitsuba 3.9.1's built-ins: load-time parameter -> its documented range (module docstring).
_REFLECTANCE = Range(0.0, 1.0)
_ALPHA = Range(0.01, 1.0, (0.05,))
_IOR = Range(1.0, 3.0, (1.0001,))
#: A conductor's complex IOR η + ik: η from 0 (the 'none' material's perfect mirror, η = 0,
#: k = 1) to 5; k > 0 for a conductor (η = k = 0 is no material: its Fresnel term is 0/0).
_ETA = Range(0.0, 5.0)
_K = Range(0.01, 10.0)
#: The principled models' roughness r, α = r² (principled.cpp): r ≥ 0.1 keeps α ≥ 0.01.
_ROUGHNESS = Range(0.1, 1.0)
#: A polarizer's or retarder's angle in degrees (theta: the axis; delta: the phase shift).
_ANGLE = Range(0.0, 180.0, (45.0, 90.0))
BUILTIN: dict[str, dict[str, Range]] = {
    "diffuse": {"reflectance": _REFLECTANCE},
    "roughconductor": {"alpha": _ALPHA, "eta": _ETA, "k": _K},
    "conductor": {"eta": _ETA, "k": _K, "specular_reflectance": _REFLECTANCE},
    "roughplastic": {"alpha": _ALPHA, "int_ior": _IOR, "diffuse_reflectance": _REFLECTANCE,
                     "specular_reflectance": _REFLECTANCE},
    "plastic": {"int_ior": _IOR, "diffuse_reflectance": _REFLECTANCE,
                "specular_reflectance": _REFLECTANCE},
    "dielectric": {"int_ior": _IOR},
    "thindielectric": {"int_ior": _IOR},
    "roughdielectric": {"alpha": _ALPHA, "int_ior": _IOR},
    "principled": {**{name: _REFLECTANCE for name in (
        "base_color", "metallic", "specular", "spec_tint", "anisotropic", "sheen",
        "sheen_tint", "clearcoat", "clearcoat_gloss", "spec_trans")}, "roughness": _ROUGHNESS},
    "principledthin": {**{name: _REFLECTANCE for name in (
        "base_color", "anisotropic", "spec_trans", "diff_trans", "sheen", "sheen_tint")},
        "roughness": _ROUGHNESS},
    "pplastic": {"alpha": _ALPHA, "int_ior": _IOR, "diffuse_reflectance": _REFLECTANCE,
                 "specular_reflectance": _REFLECTANCE},
    "polarizer": {"theta": _ANGLE, "transmittance": _REFLECTANCE},
    "retarder": {"theta": _ANGLE, "delta": _ANGLE, "transmittance": _REFLECTANCE},
    "circular": {"transmittance": _REFLECTANCE},
    "hair": {"longitudinal_roughness": Range(0.05, 1.0), "azimuthal_roughness": Range(0.05, 1.0),
             "eta": Range(1.0, 2.0), "eumelanin": Range(0.0, 5.0),
             "pheomelanin": Range(0.0, 5.0)},
}


#: The domains of Mitsuba's BSDF parameter names (its plugin reference), for a Python BSDF that
#: declares no PARAMETER_RANGES: its ``roughness`` is swept over [0.01, 1] with 0.05 and 0.1
#: (a lobe's normalization is most often wrong where it is sharp), a reflectance over [0, 1].
NAMED: dict[str, Range] = {
    **{name: _REFLECTANCE for name in (
        "reflectance", "diffuse_reflectance", "specular_reflectance", "specular_transmittance",
        "transmittance", "base_color", "albedo")},
    **{name: Range(0.01, 1.0, (0.05, 0.1)) for name in ("alpha", "alpha_u", "alpha_v",
                                                         "roughness")},
    "int_ior": _IOR, "ext_ior": Range(1.0, 3.0),
}


def parameters(plugin, spec, pinned=(), probe: bool = True) -> list:
    """The BSDF's swept parameters (:func:`phonglab.validate.ranges.parameters`)."""
    return _parameters(plugin, spec, pinned, builtin=BUILTIN, cls=mi.BSDF, word="BSDF",
                       probe=probe, named=NAMED)


def domain(plugin, spec) -> tuple[dict, str]:
    """The BSDF's declared or documented ranges (:func:`phonglab.validate.ranges.domain`)."""
    return _domain(plugin, spec, builtin=BUILTIN)
