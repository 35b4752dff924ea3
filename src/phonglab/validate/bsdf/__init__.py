"""The BSDF kind of the validator: its topics, one module per topic family.

``finite``, ``eval_pdf``, ``weight``, ``pdf``, ``component`` (:mod:`.identities`), ``chi2``
(:mod:`.sampling`), ``normalization`` (:mod:`.normalization`), ``energy`` (:mod:`.energy`;
both integrate with :mod:`.lobes`), ``reciprocity`` (:mod:`.reciprocity`),
``eval_null_transmission`` and ``eval_diffuse_reflectance`` (:mod:`.contract`),
``gradient`` (:mod:`.gradient`), ``cost`` (:mod:`.cost`); the lanes they probe
(:mod:`.lanes`), their sizes and round-off tolerances (:mod:`.config`), the topic list and the
row that checks it (:mod:`.topics`), the identity rows' reduction (:mod:`.rows`), and the table that ties them to the kind-independent runner
(:mod:`.kind`; the validator is :func:`phonglab.validate.validate_bsdf`).

Importing this package imports no Mitsuba (it declares :data:`KIND`); its modules do.
"""

from ..kind import Kind
from .topics import TOPICS


def _parts():
    """The kind's implementation module, :mod:`.kind` (imports Mitsuba: only when a part is
    first asked for)."""
    from . import kind
    return kind


#: The BSDF kind (:mod:`phonglab.validate.kind`); its parts are in :mod:`.kind`.
KIND = Kind(name="bsdf", word="BSDF", plural="BSDFs", class_name="BSDF",
            register="mi.register_bsdf", topics=TOPICS, informational=("cost",),
            bounds=("energy",), object_type="BSDF", tag="bsdf",
            implementation=_parts, conformance="docs/conformance.md", scene_noun="material")
