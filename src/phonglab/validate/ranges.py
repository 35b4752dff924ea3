r"""The parameters of a plugin that a sweep varies, and the range of each, for any kind.

A plugin is checked at a derived set of parameter points (:mod:`phonglab.validate.sweep`), not
at its defaults alone: real defects live at other settings (a lobe weight k_s/(k_d + k_s) that
is 0/0 only at k_d = k_s = 0; a normalization that is wrong only at small exponents).

Which parameters.  The scalar and spectrum parameters ``mi.traverse`` exposes (a constant
texture's ``NAME.value`` is the load-time parameter ``NAME``, set as a constant; bitmap data,
strings, positions, transforms and nested plugins are not swept), read at their loaded value
(a colour by the mean of its channels), minus the parameters the caller pins
(``--set NAME=VALUE``).  A kind's table of Mitsuba's built-ins may name load-time parameters
that differ from the traversed ones (roughplastic's ``int_ior`` is traversed as ``eta``).

The range of each, in this order of precedence:

1. declared by the plugin: a class attribute ``PARAMETER_RANGES = {"name": (lo, hi)}`` or
   ``{"name": (lo, hi, (edge, ...))}`` on the Python class (phonglab's ``lambert`` and
   ``phong`` declare theirs);
2. Mitsuba 3.9.1's documented ranges of its built-ins (each kind's ``ranges.BUILTIN`` table:
   the BSDF, emitter, integrator and phase-function folders each hold one);
3. inferred from the name (``named``): a parameter the author did not declare but named as
   Mitsuba names it (``reflectance``, ``diffuse_reflectance``, ``specular_reflectance``,
   ``alpha``, ``roughness``, ``int_ior`` ...; each kind's ``ranges.NAMED`` table) carries the
   domain Mitsuba's plugin reference gives that name, and is judged physically there (an
   albedo above 1 at ``reflectance = 1`` is a fail, not advice); the report says the domain
   was inferred from the name and how to declare another;
4. otherwise probed: the candidates 0, 10⁻⁴, d/10, d, 10d, 1, 10 and 10⁴ around the loaded
   value d, each loaded once; a value the plugin refuses at load time is outside the range,
   not a failure, and the range is [smallest accepted, largest accepted] (a parameter that
   accepts only its default is not swept).  Integrators and phase functions are not probed
   (``probe=False``: their parameters are counts and shape factors whose valid values loading
   cannot reveal): without 1. to 3. they are checked at their given point.

Edges.  Besides the ends and the middle of its range a parameter is tried at the values where
formulas break: 0 and the tiniest positive value where the range starts at 0 (1e-4: a cos^p
lobe at p → 0, a division by a reflectance), and a declared range's own edges (a huge
exponent).  A point a plugin refuses at load is reported as outside its range, not run.
"""

from __future__ import annotations

from dataclasses import dataclass

import mitsuba as mi
import numpy as np

from ..settings import PluginError, load_plugin


@dataclass(frozen=True)
class Range:
    """A parameter's valid interval and the edge values where formulas break.

    ``integer``: the parameter is a count (an integrator's ``rr_depth``): every value a sweep
    tries is an ``int``.  ``sweep_hi``: where a sweep stops when the domain is unbounded above
    (an emitter's intensity is valid up to ∞; the sweep tries 0..10); None: at ``hi``.
    """

    lo: float
    hi: float
    edges: tuple[float, ...] = ()
    integer: bool = False
    sweep_hi: float | None = None

    @classmethod
    def of(cls, spec) -> "Range":
        """A Range from ``(lo, hi)`` or ``(lo, hi, (edge, ...))`` as a plugin declares it."""
        if isinstance(spec, Range):
            return spec
        lo, hi, *rest = spec
        return cls(float(lo), float(hi), tuple(float(e) for e in (rest[0] if rest else ())))

    @property
    def top(self) -> float:
        """The largest value a sweep tries (``sweep_hi`` or ``hi``)."""
        return self.hi if self.sweep_hi is None else self.sweep_hi

    def values(self, quick: bool = False) -> tuple[float, ...]:
        """The values a sweep tries: the ends (and, unless ``quick``, the middle and the
        edges, with 1e-4 above a range that starts at 0 -- not for a count)."""
        hi = self.top
        out = [self.lo, hi]
        if not quick:
            mid = 0.5 * (self.lo + hi)
            out.insert(1, round(mid) if self.integer else mid)
            if self.lo == 0.0 and hi > 1e-4 and not self.integer:
                out.append(1e-4)
            out += [e for e in self.edges if self.lo <= e <= hi]
        if self.integer:
            out = [int(v) for v in out]
        return tuple(dict.fromkeys(out))


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


#: Traversed names that are no parameter of the plugin's physics: where it sits, how often a
#: scene picks it.
NOT_SWEPT = frozenset({"sampling_weight", "position", "to_world"})


def traversed(plugin) -> dict[str, float]:
    """Load-time name -> loaded value for each scalar/spectrum parameter ``mi.traverse``
    exposes (``NAME.value`` -> ``NAME``; dotted nested names, bitmap data and
    :data:`NOT_SWEPT` left out)."""
    params = mi.traverse(plugin)
    out = {}
    for key in params.keys():
        name = key[:-len(".value")] if key.endswith(".value") else key
        if "." in name or name in NOT_SWEPT:
            continue
        try:
            v = scalar_value(params[key])
        except (TypeError, RuntimeError):     # a value traverse cannot read (hair's sigma_a)
            continue
        if v is not None:
            out[name] = v
    return out


def domain(plugin, spec, *, builtin: dict) -> tuple[dict[str, Range], str]:
    """The declared (``PARAMETER_RANGES``) or documented (``builtin``) ranges of ``plugin``
    loaded from ``spec``, and where they come from (``declared``, ``mitsuba``); ({}, "probed")
    when it has neither."""
    type_name = spec if isinstance(spec, str) else spec["type"]
    declared = getattr(type(plugin), "PARAMETER_RANGES", None)
    if declared:
        return {k: Range.of(v) for k, v in declared.items()}, "declared"
    if type_name in builtin:
        return dict(builtin[type_name]), "mitsuba"
    return {}, "probed"


def parameters(plugin, spec, pinned=(), *, builtin: dict, cls, word: str,
               probe: bool = True, named: dict | None = None) -> list[Parameter]:
    """The parameters a sweep of ``plugin`` (of Mitsuba class ``cls``, loaded from ``spec``: a
    type name or dict) varies, with their ranges (module docstring); ``builtin``: the kind's
    table of Mitsuba's built-ins; ``named``: the domains of Mitsuba's parameter names, for a
    plugin that declares none; ``pinned`` names are left out."""
    values = traversed(plugin)
    table, source = domain(plugin, spec, builtin=builtin)
    out = []
    for name, rng in table.items():
        if name in pinned:
            continue
        # None: the plugin neither exposes nor was given it (roughplastic's int_ior, its
        # absent specular_reflectance texture): the given value is unknown, so no range value
        # is taken for it and skipped
        out.append(Parameter(name, values.get(name, _spec_value(spec, name)), rng, source))
    if source == "probed":
        for name, value in values.items():
            if name in pinned:
                continue
            if name in (named or {}) and _loads(spec, {name: named[name].lo}, cls, word) \
                    and _loads(spec, {name: named[name].top}, cls, word):
                out.append(Parameter(name, value, named[name], "named"))
            elif probe:
                rng = _probe(spec, name, value, cls, word)
                if rng is not None:
                    out.append(Parameter(name, value, rng, "probed"))
    return out


def _spec_value(spec, name):
    return scalar_value(spec.get(name)) if isinstance(spec, dict) else None


def _probe(spec, name: str, value: float, cls, word: str) -> Range | None:
    """[smallest, largest] candidate the plugin accepts at load time, or None when it
    accepts no value but its own."""
    accepted = [c for c in _candidates(value) if _loads(spec, {name: c}, cls, word)]
    if len(accepted) < 2:
        return None
    return Range(min(accepted), max(accepted))


def _loads(spec, params, cls, word: str) -> bool:
    try:
        load_plugin(spec, params, kind=cls, word=word)
    except PluginError:
        return False
    return True
