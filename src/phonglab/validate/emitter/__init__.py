"""The emitter kind of the validator: its topics, one module per topic family.

``finite``, ``weight``, ``pdf`` (:mod:`.identities`), ``chi2`` (:mod:`.sampling`), ``power``
(:mod:`.power`), ``gradient`` (:mod:`.gradient`), ``cost`` (:mod:`.cost`); the emitter placed
where it can be sampled and its reference points (:mod:`.setup`), the stacked lanes of the
identity topics (:mod:`.lanes`), sizes and seeds (:mod:`.config`), the topic list and the row
(:mod:`.topics`), Mitsuba's built-in emitters and their findings (:mod:`.builtins`,
:mod:`.signatures`), and the table that ties them to the kind-independent runner
(:mod:`.kind`: :data:`~.kind.EMITTER`, :func:`~.kind.validate_emitter`).

Importing this package imports nothing; its modules import Mitsuba.
"""
