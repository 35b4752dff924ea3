r"""The parameters of an emitter that a sweep varies, and the range of each
(:mod:`phonglab.validate.ranges` does the kind-independent part: declared, documented or
probed ranges, the points, the edges).

Mitsuba 3.9.1's built-in emitters are swept over their emitted quantity, the one parameter
every one of them scales (the plugin reference: ``intensity`` of ``point`` and ``spot`` in
W/sr, ``radiance`` of ``area`` and ``constant``, ``irradiance`` of ``directional``, ``scale``
of ``envmap``), valid from 0 (a light that emits nothing: every ratio of the identity topics
is 0/0 there) to ∞ and swept from 0 to 10; ``spot`` also over its ``cutoff_angle`` in degrees,
valid in (0, 180] and swept from a narrow cone (1°) to the hemisphere (90°; its ``beam_width``
is pinned to its default, 3/4 of the cutoff, whatever the cutoff).  A ``--set`` outside the
valid range (a negative intensity) is refused before any work.  ``sunsky`` and ``timed_sunsky`` over
their documented atmosphere (``turbidity`` in [1, 10], ground ``albedo`` in [0, 1]) and their
two scales (``sun_scale``, ``sky_scale``, as an emitted quantity); where and when the sun
stands (``latitude``, ``longitude``, ``timezone``, the date and hours, ``sun_direction``) is
its placement, like a point light's position, and not swept.  (Probed, the placement found a
real inconsistency: at latitude 0 sunsky's ``ds.pdf`` differs from ``pdf_direction`` and
``weight·pdf`` from ``eval_direction`` on the sun samples at the rim of the sun's cone, while
χ² passes: findings sunsky-sun-rim-pdf and -weight, sunsky.h:430, in the table as
``sunsky (equator)``.)  An emitter's position and transform are where it sits, not its physics: not swept.
"""

from __future__ import annotations

import mitsuba as mi

from ..ranges import Range, domain as _domain, parameters as _parameters, traversed

_EMITTED = Range(0.0, float("inf"), sweep_hi=10.0)
#: Mitsuba 3.9.1's built-in emitters: load-time parameter -> its documented range.
BUILTIN: dict[str, dict[str, Range]] = {
    "point": {"intensity": _EMITTED},
    "spot": {"intensity": _EMITTED, "cutoff_angle": Range(1.0, 180.0, sweep_hi=90.0)},
    "area": {"radiance": _EMITTED},
    "constant": {"radiance": _EMITTED},
    "directional": {"irradiance": _EMITTED},
    "envmap": {"scale": _EMITTED},
    **{name: {"turbidity": Range(1.0, 10.0), "albedo": Range(0.0, 1.0),
              "sun_scale": _EMITTED, "sky_scale": _EMITTED}
       for name in ("sunsky", "timed_sunsky")},
}

def parameters(target, spec, pinned=()) -> list:
    """The swept parameters of the emitter of ``target`` (a :class:`~.setup.Setup`)."""
    return _parameters(target.emitter, spec, pinned, builtin=BUILTIN, cls=mi.Emitter,
                       word="emitter")


def values(target) -> dict[str, float]:
    """The emitter's traversed parameter values (a documented cause's ``at``)."""
    return traversed(target.emitter)


def domain(target, spec) -> tuple[dict, str]:
    """The emitter's declared or documented ranges (:func:`phonglab.validate.ranges.domain`)."""
    return _domain(target.emitter, spec, builtin=BUILTIN)
