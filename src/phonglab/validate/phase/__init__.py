"""The phase-function kind of the validator: its topics, one module per topic family.

``finite``, ``weight``, ``pdf``, ``reciprocity`` (:mod:`.identities`), ``chi2`` and
``normalization`` (:mod:`.sampling`), ``gradient`` (:mod:`.gradient`), ``cost`` (:mod:`.cost`);
the phase function with its incident directions and the calls into Mitsuba (:mod:`.lanes`),
sizes and seeds (:mod:`.config`), the topic list and the row (:mod:`.topics`), Mitsuba's
built-in phase functions and their findings (:mod:`.builtins`), and the table that ties them to
the kind-independent runner (:mod:`.kind`: :data:`~.kind.PHASE`, :func:`~.kind.validate_phase`).

Importing this package imports nothing; its modules import Mitsuba.
"""
