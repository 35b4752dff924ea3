"""The medium kind's topics, in the order its table lists them, and its row.

A medium validator row is a :class:`phonglab.verdict.Row` whose topic must be one of
:data:`TOPICS`.  No Mitsuba import here.
"""

from __future__ import annotations

from ..kind import topic_row

#: The validator's medium topics, in the order the table lists them.
TOPICS = ("finite", "majorant", "albedo", "transmittance", "bounds", "flags", "overrides",
          "phase", "gradient", "cost")


#: A row of one of :data:`TOPICS` (:func:`phonglab.validate.kind.topic_row`).
Row = topic_row(TOPICS, "medium", __name__)
