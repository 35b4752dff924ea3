"""The result of :func:`phonglab.validate.validate_bsdf`: one :class:`Row` per check, a :class:`Report`.

The JSON form (``Report.to_json``) is ``{"meta": {...}, "results": [row, ...]}`` with each row's
fields exactly those of :class:`Row`.  A row's ``status`` is one of :data:`STATUSES`:

* ``pass``    the measured value is within the tolerance of the expected one;
* ``fail``    it is not;
* ``KNOWN``   it is not, and the caller named a documented cause for that topic (the ``known``
  option of ``validate_bsdf``); the tolerance is the same as for ``fail``;
* ``skipped`` the check does not apply (``reason`` says why).

No Mitsuba import here: reports are built, merged and printed in processes that never load it.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field

#: The validator's topics, in the order the table lists them.
TOPICS = ("finite", "eval_pdf", "weight", "pdf", "chi2", "energy", "reciprocity", "component",
          "gradient", "cost")

#: The possible values of :attr:`Row.status`.
STATUSES = ("pass", "fail", "KNOWN", "skipped")


def _plain(x):
    """``x`` with numpy scalars/arrays and non-finite floats made JSON-safe (NaN/Inf -> str)."""
    if hasattr(x, "tolist"):
        x = x.tolist()
    if isinstance(x, float):
        return x if math.isfinite(x) else str(x)
    if isinstance(x, dict):
        return {str(k): _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    return x


@dataclass
class Row:
    """One check of one topic: ``measured`` against ``expected`` within ``tolerance``."""

    topic: str
    name: str
    measured: float | None
    expected: float | None
    stderr: float | None
    tolerance: float | None
    status: str
    reason: str
    details: dict = field(default_factory=dict)

    def __post_init__(self):
        if self.topic not in TOPICS:
            raise ValueError(f"unknown topic {self.topic!r}; choose one of {', '.join(TOPICS)}")
        if self.status not in STATUSES:
            raise ValueError(f"unknown status {self.status!r}; choose one of {', '.join(STATUSES)}")

    def to_dict(self) -> dict:
        return _plain(asdict(self))

    @classmethod
    def from_dict(cls, d: dict) -> "Row":
        return cls(**{k: d.get(k) for k in ("topic", "name", "measured", "expected", "stderr",
                                             "tolerance", "status", "reason")},
                   details=d.get("details") or {})


def format_number(x) -> str:
    """A cell of the table: 4 significant digits, "-" for None."""
    if x is None:
        return "-"
    if isinstance(x, str):
        return x
    return f"{x:.4g}"


@dataclass
class Report:
    """All rows of one BSDF's validation, with ``meta`` (the BSDF, variant, seed, timings...)."""

    meta: dict
    rows: list[Row] = field(default_factory=list)

    @property
    def passed(self) -> bool:
        """True when no row has status ``fail`` (``KNOWN`` and ``skipped`` rows are allowed)."""
        return not self.failing

    @property
    def failing(self) -> list[Row]:
        return [r for r in self.rows if r.status == "fail"]

    def to_dict(self) -> dict:
        return {"meta": _plain(self.meta), "results": [r.to_dict() for r in self.rows]}

    def to_json(self, indent: int | None = 1) -> str:
        return json.dumps(self.to_dict(), indent=indent)

    @classmethod
    def from_dict(cls, d: dict) -> "Report":
        return cls(meta=dict(d.get("meta") or {}), rows=[Row.from_dict(r) for r in d["results"]])

    def table(self, rows: list[Row] | None = None) -> str:
        """A plain-text table of ``rows`` (all rows by default), one line each plus its reason."""
        return table(self.rows if rows is None else rows)


def table(rows: list[Row]) -> str:
    """Rows as aligned plain text: status, topic, name, measured, expected, tolerance, reason."""
    head = ("status", "topic", "name", "measured", "expected", "tolerance")
    body = [(r.status, r.topic, r.name, format_number(r.measured), format_number(r.expected), format_number(r.tolerance))
            for r in rows]
    widths = [max(len(str(x)) for x in col) for col in zip(head, *body)] if body else \
        [len(h) for h in head]
    lines = ["  ".join(str(x).ljust(w) for x, w in zip(head, widths)).rstrip()]
    for r, cells in zip(rows, body):
        lines.append("  ".join(str(x).ljust(w) for x, w in zip(cells, widths)).rstrip())
        if r.reason:
            lines.append(" " * (widths[0] + 2) + r.reason)
    return "\n".join(lines)
