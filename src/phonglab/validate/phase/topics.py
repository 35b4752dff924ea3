"""The phase-function kind's topics, in the order its table lists them, and its row.

A phase-function validator row is a :class:`phonglab.verdict.Row` whose topic must be one of
:data:`TOPICS`.  No Mitsuba import here.
"""

from __future__ import annotations

from ... import verdict

#: The validator's phase-function topics, in the order the table lists them.
TOPICS = ("finite", "weight", "pdf", "chi2", "normalization", "reciprocity", "gradient", "cost")


class Row(verdict.Row):
    """A :class:`phonglab.verdict.Row` of one of the phase kind's :data:`TOPICS`."""

    def __post_init__(self):
        if self.topic not in TOPICS:
            raise ValueError(f"unknown topic {self.topic!r}; choose one of {', '.join(TOPICS)}")
        super().__post_init__()
