r"""The parameters of an integrator that a sweep varies, and the range of each
(:mod:`phonglab.validate.ranges` does the kind-independent part: declared or documented
ranges, the points, the edges).

Mitsuba 3.9.1's built-in integrators are swept over the integer controls of their estimator,
never over ``max_depth``: each analytic scene sets the depth it needs (:mod:`.setup`), so the
depth is part of the scene, not of the sweep.

* ``rr_depth`` of the unbiased path tracers (``path``, ``volpath``, ``volpathmis``, ``prb``,
  ``prbvolpath``, ``ptracer``): the depth from which Russian roulette runs, from 1 (roulette
  from the first bounce; 0 is refused by the plugins) to 64 (none on any scene but the deepest
  enclosure); any larger value is valid.  Roulette changes the variance, never the mean: every identity and every bias
  scene must hold at each value.
* ``emitter_samples`` and ``bsdf_samples`` of ``direct``: the samples of each strategy per
  pixel sample, swept from 1 to 4 (valid from 1 up); the estimate averages them, so the mean
  must not move.  (0 samples of one strategy is valid in Mitsuba but leaves what only the
  other reaches unlit: a delta light without emitter samples; phonglab validates from 1.)

An integrator's other settings (``hide_emitters``, ``samples_per_pass``, a nested integrator)
are not swept.  A Python integrator is swept over its declared ``PARAMETER_RANGES`` only:
an integrator's parameters are counts and switches whose valid values loading cannot reveal
(a plugin that accepts ``rr_depth = 10⁴`` says nothing about what it means), so they are not
probed; undeclared, it is checked at its given point and the report says so.
"""

from __future__ import annotations

import re

import mitsuba as mi

from ..ranges import Range, domain as _domain, parameters as _parameters, traversed

_RR_DEPTH = Range(1, float("inf"), integer=True, sweep_hi=64)
_PER_STRATEGY = Range(1, float("inf"), integer=True, sweep_hi=4)
#: Mitsuba 3.9.1's built-in integrators: load-time parameter -> its range (module docstring).
BUILTIN: dict[str, dict[str, Range]] = {
    **{name: {"rr_depth": _RR_DEPTH}
       for name in ("path", "volpath", "volpathmis", "prb", "prbvolpath", "ptracer")},
    "direct": {"emitter_samples": _PER_STRATEGY, "bsdf_samples": _PER_STRATEGY},
}


def parameters(target, spec, pinned=()) -> list:
    """The swept parameters of the integrator of ``target`` (a :class:`~.setup.Target`)."""
    return _parameters(target.integrator, spec, pinned, builtin=BUILTIN, cls=mi.Integrator,
                       word="integrator", probe=False)


def values(target) -> dict[str, float]:
    """The integrator's parameter values a documented cause's ``at`` is held against: its
    traversed ones, and the swept controls of a built-in (:data:`BUILTIN`: ``rr_depth``,
    ``emitter_samples``, ``bsdf_samples``) as its description prints them -- Mitsuba does not
    traverse them, and at a point that does not set one (the case's own) it has its default
    (rr_depth 5, one sample of each strategy)."""
    out = traversed(target.integrator)
    spec = target.spec if isinstance(target.spec, dict) else {}
    for name in BUILTIN.get(spec.get("type"), {}):
        m = re.search(rf"\b{name} = (\d+)\b", str(target.integrator))
        if name not in out and m:
            out[name] = float(m.group(1))
    return out


def domain(target, spec) -> tuple[dict, str]:
    """The integrator's declared or documented ranges
    (:func:`phonglab.validate.ranges.domain`)."""
    return _domain(target.integrator, spec, builtin=BUILTIN)
