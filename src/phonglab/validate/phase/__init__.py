"""The phase-function kind of the validator: its topics, one module per topic family.

``finite``, ``weight``, ``pdf``, ``reciprocity`` (:mod:`.identities`), ``chi2`` and
``normalization`` (:mod:`.sampling`), ``gradient`` (:mod:`.gradient`), ``cost`` (:mod:`.cost`);
the phase function with its incident directions and the calls into Mitsuba (:mod:`.lanes`),
sizes and seeds (:mod:`.config`), the topic list and the row (:mod:`.topics`), Mitsuba's
built-in phase functions and their findings (:mod:`.builtins`), and the table that ties them to
the kind-independent runner (:mod:`.kind`; the validator is
:func:`phonglab.validate.validate_phase`).

Importing this package imports no Mitsuba (it declares :data:`KIND`); its modules do.
"""

from ..kind import Kind
from .topics import TOPICS


def _parts():
    """The kind's implementation module, :mod:`.kind` (imports Mitsuba: only when a part is
    first asked for)."""
    from . import kind
    return kind


#: The phase-function kind (:mod:`phonglab.validate.kind`); its parts are in :mod:`.kind`.
KIND = Kind(name="phase", word="phase function", plural="phase functions",
            class_name="PhaseFunction", register="mi.register_phase", topics=TOPICS,
            informational=("cost",), object_type="PhaseFunction", tag="phase",
            implementation=_parts, conformance="docs/conformance-phase.md")
