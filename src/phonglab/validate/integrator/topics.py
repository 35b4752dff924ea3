"""The integrator kind's topics, in the order its table lists them, and its row.

An integrator validator row is a :class:`phonglab.verdict.Row` (the one result record, its
JSON schema and table there) whose topic must be one of :data:`TOPICS`.  No Mitsuba import here.
"""

from __future__ import annotations

from ..kind import topic_row

#: The validator's integrator topics, in the order the table lists them.
TOPICS = ("finite", "bias", "convergence", "agreement", "gradient", "cost")


#: A row of one of :data:`TOPICS` (:func:`phonglab.validate.kind.topic_row`).
Row = topic_row(TOPICS, "integrator", __name__)
