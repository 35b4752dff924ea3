r"""The ``phase`` topic: the medium's phase function validated as a phase function, by the
phase kind itself (:data:`phonglab.validate.phase.KIND` run through
:func:`phonglab.validate.core.run`; nothing of it is copied here).

The phase function is the one the integrators use: the base class's ``phase_function()``
(include/mitsuba/render/medium.h:77, the field ``m_phase_function``), which
``Medium(const Properties&)`` takes from the medium's nested ``<phase>`` and otherwise makes
an ``isotropic`` one (src/render/medium.cpp:18-29); volpath reads it at each real collision
(src/integrators/volpath.cpp:269).  Every phase topic but the informational ``cost`` runs; each
of its rows becomes one ``phase`` row named after its topic.  Its statistical tests (the
χ² incidences) count among the medium's m, and run at the Šidák level of family × their own
count, family = ⌈m / theirs⌉, so that the medium's family-wise level stays ≤ α.
"""

from __future__ import annotations

import math

from ...settings import Loaded
from .. import core
from ..phase import KIND as PHASE
from . import lanes
from .topics import Row

#: The phase kind's topics the medium's ``phase`` topic runs.
TOPICS = tuple(t for t in PHASE.topics if t not in PHASE.informational)


def phase_function(medium):
    """The phase function the integrators use (the base class's getter)."""
    return lanes.view(medium).phase_function()


def label(phase) -> str:
    text = str(phase).splitlines()[0] if str(phase) else type(phase).__name__
    return text.rstrip("[").strip() or type(phase).__name__


def statistical_tests(medium, opts) -> int:
    """The statistical tests the phase kind makes of the medium's phase function."""
    ph = phase_function(medium)
    count = PHASE.part("statistical_tests")
    return int(count(ph, PHASE.part("options")(opts.quick, opts.seed, TOPICS), TOPICS))


def phase(medium, opts, m_tests: int) -> list[Row]:
    ph = phase_function(medium)
    name = label(ph)
    if ph is None:
        return [Row("phase", "the medium has a phase function", None, None, None, None, "fail",
                    "phase_function() is None: volpath calls it at every real collision "
                    "(src/integrators/volpath.cpp:269)", {})]
    own = max(1, statistical_tests(medium, opts))
    family = max(1, math.ceil(m_tests / own))
    report = core.run(PHASE, Loaded(ph, name, None), topics=TOPICS, seed=opts.seed,
                      quick=opts.quick, family=family)
    rows = []
    for r in report.rows:
        row = Row("phase", f"{r.topic}: {r.name}", r.measured, r.expected, r.stderr,
                  r.tolerance, r.status,
                  f"the medium's phase function ({name}) through the phase kind's "
                  f"{r.topic!r} topic: {r.reason}",
                  {**r.details, "phase_topic": r.topic, "phase_function": name,
                   "family": family})
        row.failing_lanes = r.failing_lanes
        rows.append(row)
    return rows
