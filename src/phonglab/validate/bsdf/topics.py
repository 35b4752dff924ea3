"""The BSDF kind's topics, in the order its table lists them, and its row.

A BSDF validator row is a :class:`phonglab.verdict.Row` (the one result record, its JSON schema
and table there) whose topic must be one of :data:`TOPICS`: a misspelt topic in a topic module
fails where the row is built, not later in a report.  No Mitsuba import here.
"""

from __future__ import annotations

from ... import verdict

#: The validator's BSDF topics, in the order the table lists them.
TOPICS = ("finite", "eval_pdf", "weight", "pdf", "chi2", "normalization", "energy",
          "reciprocity", "component", "eval_null_transmission", "eval_diffuse_reflectance",
          "mueller", "intensity", "mueller_identities", "mueller_reciprocity",
          "gradient", "cost")


class Row(verdict.Row):
    """A :class:`phonglab.verdict.Row` of one of the BSDF kind's :data:`TOPICS`."""

    def __post_init__(self):
        if self.topic not in TOPICS:
            raise ValueError(f"unknown topic {self.topic!r}; choose one of {', '.join(TOPICS)}")
        super().__post_init__()
