"""Physics conformance of any Mitsuba 3 BSDF: :func:`validate_bsdf` and its :class:`~phonglab.verdict.Report`.

Topics (one home each): ``finite``, ``eval_pdf``, ``weight``, ``pdf``, ``component``
(:mod:`.identities`), ``chi2`` (:mod:`.sampling`), ``energy`` (:mod:`.energy`),
``reciprocity`` (:mod:`.reciprocity`), ``gradient`` (:mod:`.gradient`), ``cost``
(:mod:`.cost`).  Sizes and tolerances: :mod:`.config`; the topic list and the validator's row:
:mod:`.topics`; reports (rows, JSON, table): :mod:`phonglab.verdict`.

Importing this package does not import Mitsuba (the CLI starts fast); ``validate_bsdf`` does.
"""

from ..verdict import Report
from .topics import TOPICS

__all__ = ["TOPICS", "validate_bsdf"]


def validate_bsdf(spec, **options) -> Report:
    """Validate a BSDF on every topic; see :func:`phonglab.validate.core.validate_bsdf`."""
    from .core import validate_bsdf as run   # lazy: imports Mitsuba (seconds) only when called

    return run(spec, **options)
