"""The integrator kind's topics, in the order its table lists them, and its row.

An integrator validator row is a :class:`phonglab.verdict.Row` (the one result record, its
JSON schema and table there) whose topic must be one of :data:`TOPICS`.  No Mitsuba import here.
"""

from __future__ import annotations

from ... import verdict

#: The validator's integrator topics, in the order the table lists them.
TOPICS = ("finite", "bias", "convergence", "agreement", "gradient", "cost")


class Row(verdict.Row):
    """A :class:`phonglab.verdict.Row` of one of the integrator kind's :data:`TOPICS`."""

    def __post_init__(self):
        if self.topic not in TOPICS:
            raise ValueError(f"unknown topic {self.topic!r}; choose one of {', '.join(TOPICS)}")
        super().__post_init__()
