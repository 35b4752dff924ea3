"""The BSDF kind's topics, in the order its table lists them, and its row.

A BSDF validator row is a :class:`phonglab.verdict.Row` (the one result record, its JSON schema
and table there) whose topic must be one of :data:`TOPICS`: a misspelt topic in a topic module
fails where the row is built, not later in a report.  No Mitsuba import here.
"""

from __future__ import annotations

from ..kind import topic_row

#: The validator's BSDF topics, in the order the table lists them.
TOPICS = ("finite", "eval_pdf", "weight", "pdf", "chi2", "normalization", "energy",
          "reciprocity", "component", "eval_null_transmission", "eval_diffuse_reflectance",
          "mueller", "intensity", "mueller_identities", "mueller_reciprocity",
          "gradient", "cost")


#: A row of one of :data:`TOPICS` (:func:`phonglab.validate.kind.topic_row`).
Row = topic_row(TOPICS, "BSDF", __name__)
