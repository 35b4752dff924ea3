"""The integrator kind of the validator: its topics, one module per topic family.

``finite``, ``bias``, ``convergence`` on the analytic scenes (:mod:`.analytic`, the scenes and
their values in :mod:`.scenes`), ``agreement`` against Mitsuba's ``path`` (:mod:`.agreement`),
``gradient`` of AD integrators (:mod:`.gradient`), ``cost`` (:mod:`.cost`); the integrator
rebuilt at each scene's depth and what kind of estimator it is (:mod:`.setup`), sizes and
seeds (:mod:`.config`), the topic list and the row (:mod:`.topics`), and the table that ties
them to the kind-independent runner (:mod:`.kind`: :data:`~.kind.INTEGRATOR`,
:func:`~.kind.validate_integrator`).

Importing this package imports nothing; its modules import Mitsuba.
"""
