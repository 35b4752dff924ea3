r"""The parameters of a medium that a sweep varies, and the range of each
(:mod:`phonglab.validate.ranges` does the kind-independent part: declared or documented
ranges, the points, the edges).

Mitsuba 3.9.1's plugin reference (the ``pluginparameters`` blocks of src/media/homogeneous.cpp
and heterogeneous.cpp): ``homogeneous`` takes ``albedo`` (float, spectrum or volume; a
single-scattering albedo, so [0, 1]), ``sigma_t`` (float or spectrum, an extinction
coefficient in inverse scene units: [0, ∞)) and ``scale`` (float, applied to the extinction:
[0, ∞)); ``heterogeneous`` takes the same names, its albedo and extinction as volumes, which
a sweep does not replace (a grid is not a value): only its ``scale`` is swept.  An unbounded
range is swept up to 10 (``sweep_hi``): optical depths up to 40 across the probe box, where
transmittance is e⁻⁴⁰ and tracking still ends every walk.  Both start at 0, so 0 (an empty
medium: σ_t = 0, no collision is ever sampled, the albedo undefined) and 1e-4 are tried.

A Python medium is swept over its declared ``PARAMETER_RANGES`` only, never probed (its
parameters' valid values loading cannot reveal); undeclared, it is checked at its given point
and the report says so.
"""

from __future__ import annotations

import math

import mitsuba as mi

from ..ranges import Range, domain as _domain, parameters as _parameters

#: An extinction-like parameter: valid on [0, ∞), swept to 10.
_EXTINCTION = Range(0.0, math.inf, sweep_hi=10.0)

#: Mitsuba 3.9.1's built-in media: load-time parameter -> its range.
BUILTIN: dict[str, dict[str, Range]] = {
    "homogeneous": {"albedo": Range(0.0, 1.0), "sigma_t": _EXTINCTION, "scale": _EXTINCTION},
    "heterogeneous": {"scale": _EXTINCTION},
}


def parameters(medium, spec, pinned=()) -> list:
    """The swept parameters of ``medium`` (the loaded ``mi.Medium``)."""
    return _parameters(medium, spec, pinned, builtin=BUILTIN, cls=mi.Medium, word="medium",
                       probe=False)


def domain(medium, spec) -> tuple[dict, str]:
    """The medium's declared or documented ranges (:func:`phonglab.validate.ranges.domain`)."""
    return _domain(medium, spec, builtin=BUILTIN)
