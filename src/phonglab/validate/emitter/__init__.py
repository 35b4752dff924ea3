"""The emitter kind of the validator: its topics, one module per topic family.

``finite``, ``weight``, ``pdf`` (:mod:`.identities`), ``chi2`` (:mod:`.sampling`), ``power``
(:mod:`.power`), ``gradient`` (:mod:`.gradient`), ``cost`` (:mod:`.cost`); the emitter placed
where it can be sampled and its reference points (:mod:`.setup`), the stacked lanes of the
identity topics (:mod:`.lanes`), sizes and seeds (:mod:`.config`), the topic list and the row
(:mod:`.topics`), Mitsuba's built-in emitters and their findings (:mod:`.builtins`,
:mod:`.signatures`), and the table that ties them to the kind-independent runner
(:mod:`.kind`; the validator is :func:`phonglab.validate.validate_emitter`).

Importing this package imports no Mitsuba (it declares :data:`KIND`); its modules do.
"""

from ..kind import Kind
from .topics import TOPICS


def _parts():
    """The kind's implementation module, :mod:`.kind` (imports Mitsuba: only when a part is
    first asked for)."""
    from . import kind
    return kind


#: The emitter kind (:mod:`phonglab.validate.kind`); its parts are in :mod:`.kind`.
KIND = Kind(name="emitter", word="emitter", plural="emitters", class_name="Emitter",
            register="mi.register_emitter", topics=TOPICS, informational=("cost",),
            bounds=("power",), object_type="Emitter", tag="emitter",
            implementation=_parts, conformance="docs/conformance-emitters.md",
            load_options=("shape",))
