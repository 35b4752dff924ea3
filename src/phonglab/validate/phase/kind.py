"""The phase-function kind of the validator: ``mi.PhaseFunction``, its topics table, its
statistical tests, its loading and :func:`validate_phase`.

The statistical tests of a phase function are its χ² incidences (:data:`.lanes.INCIDENCES`);
``normalization`` is a deterministic quadrature with a stated error bound, the other topics
are identities at float32 round-off, a gradient check, or informational (``cost``).  The
direction convention (``mi.wi`` points back along the incoming light; hg with g > 0 peaks at
wo = −wi) is :mod:`.lanes`'.
"""

from __future__ import annotations

import mitsuba as mi
import numpy as np

from ...settings import Loaded
from ...verdict import Report
from .. import core
from ..inputs import check_topics
from . import lanes
from .config import options
from .cost import cost
from .gradient import gradient
from .identities import finite, pdf, reciprocity, weight
from .sampling import chi2, normalization
from .topics import TOPICS


# Mitsuba 3.9.1 names the call mi.register_phase (core.REGISTER_CALLS lists
# "register_phasefunction", which does not exist): record it too, so that core.load_plugins sees
# a --plugin file register its phase function.  To be folded into core.REGISTER_CALLS.
core.REGISTER_CALLS.setdefault("register_phase", "phase function")


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


#: The phase-function kind: what :mod:`phonglab.validate.core` runs (its plugin is the
#: ``mi.PhaseFunction`` itself; every topic builds its own MediumInteraction3f, :mod:`.lanes`).
PHASE = core.Kind(name="phase", word="phase function", class_name="PhaseFunction",
                  register="mi.register_phase", topics=TOPICS, options=options,
                  statistical_tests=statistical_tests, runners=runners,
                  informational=("cost",), values=values)


def prepare(spec, *, variant=None, params=None, plugins=()) -> Loaded:
    """Set the variant, run the ``--plugin`` files, load the phase function
    (:func:`phonglab.validate.core.prepare`); bad input raises
    :class:`~phonglab.validate.inputs.ValidateError`.  Its plugin is the ``mi.PhaseFunction``;
    the topics place it at ``lanes.interaction(wi)`` (a MediumInteraction3f with wi and
    sh_frame = Frame3f(wi)) with ``lanes.context()`` (a PhaseFunctionContext without a
    sampler)."""
    return core.prepare(PHASE, spec, variant=variant, params=params, plugins=plugins)


def validate_phase(spec, *, variant=None, params=None, topics=None, seed=0, quick=False,
                   known=None, plugins=(), family=1, sizes=None) -> Report:
    """Validate one phase function on every topic (or ``topics``).

    ``spec``: a plugin type name, a dict for ``mi.load_dict``, an XML file holding one
    ``<phase>``, or a loaded ``mi.PhaseFunction``.  ``known``, ``plugins``, ``family``,
    ``sizes``: as for :func:`phonglab.validate.bsdf.kind.validate_bsdf`.  Bad input raises
    :class:`~phonglab.validate.inputs.ValidateError` with one sentence.
    """
    topics = check_topics(topics, TOPICS)
    target = prepare(spec, variant=variant, params=params, plugins=plugins)
    return core.run(PHASE, target, topics=topics, seed=seed, quick=quick, known=known,
                    family=family, sizes=sizes)


def is_phase(spec) -> bool:
    """Whether ``spec`` names a phase-function plugin (:func:`core.names_plugin`)."""
    return core.names_plugin(spec, mi.PhaseFunction, mi.ObjectType.PhaseFunction, "phase")
