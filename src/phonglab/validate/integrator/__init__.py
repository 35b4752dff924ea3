"""The integrator kind of the validator: its topics, one module per topic family.

``finite``, ``bias``, ``convergence`` on the analytic scenes (:mod:`.analytic`, the scenes and
their values in :mod:`.scenes`), ``agreement`` against Mitsuba's ``path`` (:mod:`.agreement`),
``gradient`` of AD integrators (:mod:`.gradient`), ``cost`` (:mod:`.cost`); the integrator
rebuilt at each scene's depth and what kind of estimator it is (:mod:`.setup`), sizes and
seeds (:mod:`.config`), the topic list and the row (:mod:`.topics`), and the table that ties
them to the kind-independent runner (:mod:`.kind`; the validator is
:func:`phonglab.validate.validate_integrator`).

Importing this package imports no Mitsuba (it declares :data:`KIND`); its modules do.
"""

from ..kind import Kind
from .topics import TOPICS


def _parts():
    """The kind's implementation module, :mod:`.kind` (imports Mitsuba: only when a part is
    first asked for)."""
    from . import kind
    return kind


#: The integrator kind (:mod:`phonglab.validate.kind`); its parts are in :mod:`.kind`.
KIND = Kind(name="integrator", word="integrator", plural="integrators", class_name="Integrator",
            register="mi.register_integrator", topics=TOPICS, informational=("cost",),
            object_type="Integrator", tag="integrator",
            implementation=_parts, conformance="docs/conformance-integrators.md")
