r"""The medium kind of the validator: ``mi.Medium``, its topics table, its statistical tests
and the check of a Python medium's returns (the package face :mod:`phonglab.validate` gives
it ``validate_medium``).

The statistical tests of a medium are the ``transmittance`` topic's (one per ray, channel
and tracking estimator, :func:`.tracking.statistical_tests`) and those the phase kind makes of
its phase function (:func:`.scattering.statistical_tests`): each at the Šidák level of their
sum, m.  The other topics are deterministic: counts of bad lanes, float32 identities, bounds.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi

from ..conformance import known_of
from ..phase.kind import values  # noqa: F401 (the kind's part "values": every scalar traversed)
from ..returns import checked, defines
from . import lanes
from .coefficients import albedo, bounds, finite, flags, majorant
from .config import options  # noqa: F401 (the kind's part "options")
from .cost import cost
from .gradient import gradient
from .overrides import overrides
from .ranges import domain, parameters  # noqa: F401 (the kind's parts "domain", "parameters")
from .scattering import phase, statistical_tests as phase_tests
from .tracking import statistical_tests as tracking_tests, transmittance


def statistical_tests(medium, opts, topics) -> int:
    """m: the transmittance tests and the phase function's χ² tests."""
    m = tracking_tests(opts) if "transmittance" in topics else 0
    m += phase_tests(medium, opts) if "phase" in topics else 0
    return max(1, m)


def runners(medium, opts, topics, m: int) -> dict:
    return {
        "finite": lambda: finite(medium, opts),
        "majorant": lambda: majorant(medium, opts),
        "albedo": lambda: albedo(medium, opts),
        "transmittance": lambda: transmittance(medium, opts, m),
        "bounds": lambda: bounds(medium, opts),
        "flags": lambda: flags(medium, opts),
        "overrides": lambda: overrides(medium, opts),
        "phase": lambda: phase(medium, opts, m),
        "gradient": lambda: gradient(medium, opts),
        "cost": lambda: cost(medium, opts),
    }


def returns(plugin, name: str = "medium") -> None:
    """A Python medium's ``intersect_aabb``, ``get_majorant`` and
    ``get_scattering_coefficients`` (those its class defines) return what the trampoline
    casts to (src/render/python/medium_v.cpp:22-33): (Mask, Float, Float), an
    UnpolarizedSpectrum, and (σ_s, σ_n, σ_t)."""
    if not isinstance(plugin, mi.Medium) or not dr.is_jit_v(mi.Float):
        return
    ray = lanes.ray([[0.0, 0.0, -1.0]], [[0.0, 0.0, 1.0]])
    mei = lanes.interaction([[0.0, 0.0, -1.0]], [[0.0, 0.0, 1.0]], [1.0])
    active = mi.Bool(True)
    for method, args, expects in (
            ("intersect_aabb", (ray,), "a tuple (hit: mi.Bool, mint: mi.Float, maxt: "
                                       "mi.Float), e.g. return bbox.ray_intersect(ray)"),
            ("get_majorant", (mei, active), "one mi.UnpolarizedSpectrum or number"),
            ("get_scattering_coefficients", (mei, active),
             "a tuple (sigma_s, sigma_n, sigma_t) of mi.UnpolarizedSpectrum, sigma_n the "
             "null-collision coefficient majorant − sigma_t")):
        if defines(plugin, method):
            checked(lanes.view(plugin), "medium", name, method, args, expects)


def known_for(name: str, params: dict | None = None) -> dict:
    """The conformance table's findings of the Mitsuba built-in medium ``name``."""
    return known_of(catalogue().cases(), name)


def catalogue():
    """The medium conformance table (:mod:`.builtins`)."""
    from .builtins import CATALOGUE
    return CATALOGUE
