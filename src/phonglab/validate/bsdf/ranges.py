r"""The parameters of a BSDF that a sweep varies, and the range of each.

A BSDF is checked at a derived set of parameter points (:mod:`phonglab.validate.sweep`), not
at its defaults alone: real defects live at other settings (a lobe weight k_s/(k_d + k_s) that
is 0/0 only at k_d = k_s = 0; a normalization that is wrong only at small exponents).

Which parameters.  The scalar and spectrum parameters ``mi.traverse`` exposes (a constant
texture's ``NAME.value`` is the load-time parameter ``NAME``, set as a constant; bitmap data,
strings and nested plugins are not swept), read at their loaded value (a colour by the mean of
its channels), minus the parameters the caller pins (``--set NAME=VALUE``).  A built-in whose
load-time names differ from the traversed ones (roughplastic's ``int_ior`` is traversed as
``eta``) is swept by the load-time names of its table below.

The range of each, in this order of precedence:

1. declared by the plugin: a class attribute ``PARAMETER_RANGES = {"name": (lo, hi)}`` or
   ``{"name": (lo, hi, (edge, ...))}`` on the Python class (phonglab's ``lambert`` and
   ``phong`` declare theirs);
2. Mitsuba 3.9.1's documented ranges of its built-ins (:data:`BUILTIN`, from the plugin
   reference: reflectances in [0, 1], microfacet roughness α, where the docs give 0.001-0.01
   as "very smooth" to 0.3+ as "rough", IORs between equal (1) and the densest tabulated
   materials (≈ 2.4 for diamond; 3 here), a conductor's η ∈ [0, 5] and k ∈ [0.01, 10] (η = k
   = 0 is no material)); ``alpha`` is held ≥ 0.01, the smoothest lobe the χ² bins resolve;
3. otherwise probed: the candidates 0, 10⁻⁴, d/10, d, 10d, 1, 10 and 10⁴ around the loaded
   value d, each loaded once; a value the plugin refuses at load time is outside the range,
   not a failure, and the range is [smallest accepted, largest accepted] (a parameter that
   accepts only its default is not swept).

Edges.  Besides the ends and the middle of its range a parameter is tried at the values where
formulas break: 0 and the tiniest positive value where the range starts at 0 (1e-4: a cos^p
lobe at p → 0, a division by a reflectance), and a declared range's own edges (a huge
exponent).  A point a plugin refuses at load (k_d + k_s > 1 for phong at "all at maximum")
is reported as outside the plugin's range, not run.
"""

from __future__ import annotations

from dataclasses import dataclass

import mitsuba as mi
import numpy as np

from ...settings import PluginError, load_plugin


@dataclass(frozen=True)
class Range:
    """A parameter's valid interval and the edge values where formulas break."""

    lo: float
    hi: float
    edges: tuple[float, ...] = ()

    @classmethod
    def of(cls, spec) -> "Range":
        """A Range from ``(lo, hi)`` or ``(lo, hi, (edge, ...))`` as a plugin declares it."""
        if isinstance(spec, Range):
            return spec
        lo, hi, *rest = spec
        return cls(float(lo), float(hi), tuple(float(e) for e in (rest[0] if rest else ())))

    def values(self, quick: bool = False) -> tuple[float, ...]:
        """The values a sweep tries: the ends (and, unless ``quick``, the middle and the
        edges, with 1e-4 above a range that starts at 0)."""
        out = [self.lo, self.hi]
        if not quick:
            out.insert(1, 0.5 * (self.lo + self.hi))
            if self.lo == 0.0 and self.hi > 1e-4:
                out.append(1e-4)
            out += [e for e in self.edges if self.lo <= e <= self.hi]
        return tuple(dict.fromkeys(out))


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

def _candidates(d: float) -> list[float]:
    """Probe candidates around a loaded value d (module docstring, item 3)."""
    return sorted({0.0, 1e-4, d / 10, d, 10 * d, 1.0, 10.0, 1e4})


@dataclass(frozen=True)
class Parameter:
    """One swept parameter: its load-time name, its loaded value, its range and where the
    range came from (``declared``, ``mitsuba``, ``probed``)."""

    name: str
    value: float | None        #: None: not exposed by the plugin and not in its spec
    range: Range
    source: str


def scalar_value(v) -> float | None:
    """A traversed value as one float (a colour's channel mean), or None when it is none."""
    if isinstance(v, (bool, str)) or v is None:
        return None
    try:
        a = np.array(v, dtype=np.float64).ravel()
    except (TypeError, ValueError):
        return None
    return float(a.mean()) if 0 < a.size <= 4 and np.all(np.isfinite(a)) else None


def traversed(plugin) -> dict[str, float]:
    """Load-time name -> loaded value for each scalar/spectrum parameter ``mi.traverse``
    exposes (``NAME.value`` -> ``NAME``; dotted nested names and bitmap data left out)."""
    params = mi.traverse(plugin)
    out = {}
    for key in params.keys():
        name = key[:-len(".value")] if key.endswith(".value") else key
        if "." in name:
            continue
        try:
            v = scalar_value(params[key])
        except (TypeError, RuntimeError):     # a value traverse cannot read (hair's sigma_a)
            continue
        if v is not None:
            out[name] = v
    return out


def parameters(plugin, spec, pinned=(), probe: bool = True) -> list[Parameter]:
    """The parameters a sweep of ``plugin`` (loaded from ``spec``: a type name or dict)
    varies, with their ranges (module docstring); ``pinned`` names are left out."""
    type_name = spec if isinstance(spec, str) else spec["type"]
    declared = getattr(type(plugin), "PARAMETER_RANGES", None)
    values = traversed(plugin)
    if declared:
        table, source = {k: Range.of(v) for k, v in declared.items()}, "declared"
    elif type_name in BUILTIN:
        table, source = BUILTIN[type_name], "mitsuba"
    else:
        table, source = {}, "probed"
    out = []
    for name, rng in table.items():
        if name in pinned:
            continue
        # None: the plugin neither exposes nor was given it (roughplastic's int_ior, its
        # absent specular_reflectance texture): the given value is unknown, so no range value
        # is taken for it and skipped
        out.append(Parameter(name, values.get(name, _spec_value(spec, name)), rng, source))
    if source == "probed" and probe:
        for name, value in values.items():
            if name not in pinned:
                rng = _probe(spec, name, value)
                if rng is not None:
                    out.append(Parameter(name, value, rng, "probed"))
    return out


def _spec_value(spec, name):
    return scalar_value(spec.get(name)) if isinstance(spec, dict) else None


def _probe(spec, name: str, value: float) -> Range | None:
    """[smallest, largest] candidate the plugin accepts at load time, or None when it
    accepts no value but its own."""
    accepted = [c for c in _candidates(value) if _loads(spec, {name: c})]
    if len(accepted) < 2:
        return None
    return Range(min(accepted), max(accepted))


def _loads(spec, params) -> bool:
    try:
        load_plugin(spec, params, kind=mi.BSDF, word="BSDF")
    except PluginError:
        return False
    return True
