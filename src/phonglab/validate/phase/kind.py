"""The phase-function kind of the validator: ``mi.PhaseFunction``, its topics table, its
statistical tests and its loading (the package face :mod:`phonglab.validate` gives it
``validate_phase``).

The statistical tests of a phase function are its χ² incidences (:data:`.lanes.INCIDENCES`);
``normalization`` is a deterministic quadrature with a stated error bound, the other topics
are identities at float32 round-off, a gradient check, or informational (``cost``).  The
direction convention (``mi.wi`` points back along the incoming light; hg with g > 0 peaks at
wo = −wi) is :mod:`.lanes`'.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

from ..conformance import known_of
from . import lanes, ranges
from ..returns import checked, defines
from .config import options
from .cost import cost
from .gradient import gradient
from .identities import finite, pdf, reciprocity, weight
from .sampling import chi2, normalization


def statistical_tests(phase, opts, topics) -> int:
    """m: one χ² test per incidence."""
    return len(lanes.INCIDENCES) if "chi2" in topics else 1


def runners(phase, opts, topics, m: int) -> dict:
    return {
        "finite": lambda: finite(phase, opts),
        "weight": lambda: weight(phase, opts),
        "pdf": lambda: pdf(phase, opts),
        "chi2": lambda: chi2(phase, opts, m),
        "normalization": lambda: normalization(phase, opts),
        "reciprocity": lambda: reciprocity(phase, opts),
        "gradient": lambda: gradient(phase, opts),
        "cost": lambda: cost(phase, opts),
    }


def returns(plugin, name: str = "phase function") -> None:
    """A Python phase function's ``sample`` and ``eval_pdf`` (those its class defines) return
    what Mitsuba casts to (Vector3f wo, Spectrum weight, Float pdf) and (Spectrum, Float)
    (:mod:`phonglab.validate.returns`)."""
    if not isinstance(plugin, mi.PhaseFunction) or mi.is_polarized:
        return
    ctx = mi.PhaseFunctionContext(None)
    mei = dr.zeros(mi.MediumInteraction3f)
    mei.wi = dr.normalize(mi.Vector3f(0.3, 0.2, 0.9))
    mei.sh_frame = mi.Frame3f(mei.wi)
    mei.t = mi.Float(0.0)
    active = mi.Bool(True)
    wo = dr.normalize(mi.Vector3f(-0.2, 0.1, 0.9))
    for method, args, expects in (
            ("sample", (ctx, mei, mi.Float(0.5), mi.Point2f(0.3, 0.6), active),
             "a tuple (wo: mi.Vector3f, weight: mi.Spectrum, pdf: mi.Float), e.g. return wo, "
             "weight, pdf"),
            ("eval_pdf", (ctx, mei, wo, active),
             "a tuple (value: mi.Spectrum, pdf: mi.Float), e.g. return value, pdf")):
        if defines(plugin, method):
            checked(lanes.view(plugin), "phase function", name, method, args, expects)


def values(phase) -> dict:
    """The phase function's scalar parameters (``g``, ``weight.value.value``, ...)."""
    out = {}
    params = mi.traverse(phase)
    for k in params.keys():
        try:
            a = np.array(params[k], dtype=np.float64).ravel()
        except Exception:
            continue
        if a.size == 1:
            out[k] = float(a[0])
    return out



#: The sweep's parameters and the ranges a ``--set`` must lie in.
parameters = ranges.parameters
domain = ranges.domain



def known_for(name: str, params: dict | None = None) -> dict:
    """The conformance table's findings of the Mitsuba built-in phase function ``name``."""
    return known_of(catalogue().cases(), name)


def catalogue():
    """The phase-function conformance table (:mod:`.builtins`)."""
    from .builtins import CATALOGUE
    return CATALOGUE
