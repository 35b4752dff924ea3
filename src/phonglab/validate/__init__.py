"""Physics conformance of any Mitsuba 3 BSDF: :func:`validate_bsdf` and its report.

The runner is kind-independent (:mod:`.core`: guarded topics, Šidák over the statistical
rows, KNOWN causes, the report); a plugin kind brings its topics.  The BSDF kind
(:mod:`.bsdf`): ``finite``, ``eval_pdf``, ``weight``, ``pdf``, ``component``
(:mod:`.bsdf.identities`), ``chi2`` (:mod:`.bsdf.sampling`), ``energy`` (:mod:`.bsdf.energy`),
``reciprocity`` (:mod:`.bsdf.reciprocity`), ``gradient`` (:mod:`.bsdf.gradient`), ``cost``
(:mod:`.bsdf.cost`); sizes and tolerances: :mod:`.bsdf.config`; the topic list and the
BSDF rows: :mod:`.bsdf.topics`.  Rows and reports: :mod:`phonglab.verdict`; user input:
:mod:`.inputs` and :mod:`phonglab.settings`; Mitsuba's built-ins and their findings:
:mod:`.builtins`; many cases as jobs: :mod:`.batch`.

The emitter kind (:mod:`.emitter`, :func:`validate_emitter`): ``finite``, ``weight``, ``pdf``,
``chi2``, ``power``, ``gradient``, ``cost``.  The integrator kind (:mod:`.integrator`,
:func:`validate_integrator`): ``finite``, ``bias``, ``convergence``, ``agreement``,
``gradient``, ``cost``.

Importing this package does not import Mitsuba (the CLI starts fast); ``validate_bsdf`` and
``validate_emitter`` and ``validate_integrator`` do.
"""

from ..verdict import Report
from .bsdf.topics import TOPICS

__all__ = ["TOPICS", "validate_bsdf", "validate_emitter", "validate_integrator"]


def validate_bsdf(spec, **options) -> Report:
    """Validate a BSDF on every topic; see :func:`phonglab.validate.bsdf.kind.validate_bsdf`."""
    from .bsdf.kind import validate_bsdf as run   # lazy: imports Mitsuba (seconds) only when called

    return run(spec, **options)


def validate_emitter(spec, **options) -> Report:
    """Validate an emitter on every emitter topic; see
    :func:`phonglab.validate.emitter.kind.validate_emitter`."""
    from .emitter.kind import validate_emitter as run   # lazy, as validate_bsdf

    return run(spec, **options)


def validate_integrator(spec, **options) -> Report:
    """Validate an integrator on every integrator topic; see
    :func:`phonglab.validate.integrator.kind.validate_integrator`."""
    from .integrator.kind import validate_integrator as run   # lazy, as validate_bsdf

    return run(spec, **options)
