r"""The parameters of a phase function that a sweep varies, and the range of each
(:mod:`phonglab.validate.ranges` does the kind-independent part: declared or documented
ranges, the points, the edges).

Mitsuba 3.9.1's ``hg`` is swept over its asymmetry ``g`` in [−0.99, 0.99] (the plugin
reference: g ∈ (−1, 1); ±1 is a delta), through isotropic scattering at g = 0 (the middle)
and ±0.5.  hg's small non-zero |g| (1e-5, where its sampling loses float32 precision) is a
case of the conformance table, not a sweep point.  The other built-ins have no scalar
parameter to sweep (``isotropic``, ``rayleigh``), take a table or a volume (``tabphase``,
``sggx``), or nest other phase functions (``blendphase``: its ``weight`` is not swept,
because at 0 and 1 its gradient is one-sided, which the gradient topic's central difference
does not take).

A Python phase function is swept over its declared ``PARAMETER_RANGES`` only, never probed:
a Henyey–Greenstein written with a plain-float ``g`` loads at g = 10, where its formula is no
density at all, and that says nothing about the plugin's correctness in (−1, 1).
Undeclared, it is checked at its given point and the report says so.
"""

from __future__ import annotations

import mitsuba as mi

from ..ranges import Range, domain as _domain, parameters as _parameters, traversed

#: Mitsuba 3.9.1's built-in phase functions: load-time parameter -> its range.
BUILTIN: dict[str, dict[str, Range]] = {
    "hg": {"g": Range(-0.99, 0.99, (-0.5, 0.5))},
}


def parameters(phase, spec, pinned=()) -> list:
    """The swept parameters of ``phase`` (the loaded ``mi.PhaseFunction``)."""
    return _parameters(phase, spec, pinned, builtin=BUILTIN, cls=mi.PhaseFunction,
                       word="phase function", probe=False)


def domain(phase, spec) -> tuple[dict, str]:
    """The phase function's declared or documented ranges
    (:func:`phonglab.validate.ranges.domain`)."""
    return _domain(phase, spec, builtin=BUILTIN)


__all__ = ["BUILTIN", "domain", "parameters", "traversed"]
