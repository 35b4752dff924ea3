"""The one result record of phonglab: a :class:`Row` per verdict, a :class:`Report` of rows.

Every harness writes its verdicts here: ``phonglab validate`` (one report per plugin, a row's
``topic`` one of its kind's, :attr:`phonglab.validate.kind.Kind.topics`) and ``phonglab
check`` (one report per run, ``topic`` the check's name).  A harness checks its own topic names
(a kind's row, :func:`phonglab.validate.kind.topic_row`, refuses any other); this module knows
none.

A row compares ``measured`` with ``expected`` within ``tolerance`` (``stderr``: the Monte Carlo
standard error of ``measured``, None or 0 for a deterministic quantity); ``reason`` says what
is compared and why the verdict is what it is, ``details`` holds what a reader needs to find a
problem (JSON-able data).  Its ``status`` is one of :data:`STATUSES`:

* ``pass``    the measured value is within the tolerance of the expected one;
* ``fail``    it is not;
* ``KNOWN``   it is not, and the harness names a documented cause (``reason`` or
  ``details["known_issue"]``); the tolerance is the same as for ``fail``;
* ``skipped`` the check does not apply (``reason`` says why);
* ``advice``  a physical bound (a BSDF's albedo ≤ 1, an emitter's power) exceeded at a
  parameter point outside the plugin's declared or documented domain (a value only probed at
  load time: a plain-float ``kd`` accepted up to 10⁴): not a fail, the plugin should declare
  its range or refuse the value (``reason`` says where the excess starts).

Two keys of ``details`` have a meaning here: ``not_applicable`` (:data:`NOT_APPLICABLE`), on a
skipped row, says the check does not apply to what the plugin or the variant is (a polarized
topic in an RGB variant), as opposed to a check that could not judge what it should have
(:func:`phonglab.validate.core.not_covered`); and ``relation`` (``"=="``, ``"<="``, ``">="``), how
``measured`` is held against ``expected`` ± ``tolerance`` (``<=``: measured ≤ expected +
tolerance); the table shows a one-sided row's expected value as ``≤ x`` or ``≥ x``.  A row
without it states its comparison in ``reason``.

JSON (:meth:`Report.to_json`; :func:`phonglab.engine.outputs.write_json` writes a report's
:meth:`~Report.to_dict` to a file): ``{"meta": {...}, "results": [row, ...]}``
with each row's fields exactly those of :class:`Row` (``point`` only on a sweep's rows, ``doc``
only on a validator's), made
strict-JSON-safe by
:func:`jsonable` (numpy scalars and arrays to Python numbers and lists, NaN/Inf to strings,
paths to strings).  Text: :func:`table`; the HTML report (:mod:`phonglab.validate.html`)
formats its cells with the same :func:`cells`.

No Mitsuba import here: reports are built, merged and printed in processes that never load it.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path


#: The possible values of :attr:`Row.status`.
STATUSES = ("pass", "fail", "KNOWN", "skipped", "advice")

#: The ``details`` key of a skipped row whose check genuinely does not apply (module docstring).
NOT_APPLICABLE = "not_applicable"

#: How ``details["relation"]`` shows on the expected value of a table row.
RELATION_PREFIX = {"==": "", "<=": "≤ ", ">=": "≥ "}


def jsonable(x):
    """``x`` made strict-JSON-safe: numpy to Python, paths to str, NaN/Inf to "nan"/"inf"."""
    if hasattr(x, "tolist"):
        x = x.tolist()
    if isinstance(x, float):
        return x if math.isfinite(x) else str(x)
    if isinstance(x, dict):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, Path):
        return str(x)
    return x


@dataclass
class Row:
    """One verdict: ``measured`` against ``expected`` within ``tolerance``, on one topic."""

    topic: str
    name: str
    measured: float | None
    expected: float | None
    stderr: float | None
    tolerance: float | None
    status: str
    reason: str
    details: dict = field(default_factory=dict)
    #: The parameter point the row was measured at, when a sweep measured it at several
    #: (parameter -> value, ``{}`` for the given point); None otherwise, and then the row's
    #: JSON has no ``point`` key.
    point: dict | None = None
    #: The page of the docs site that explains the row's topic, relative to the site's root
    #: (``topics/bsdf/energy.html``; set by the validator:
    #: :func:`phonglab.validate.kind.topic_page`, linked against
    #: :data:`phonglab.validate.kind.DOCS_URL`); None for rows of other harnesses, and then the
    #: row's JSON has no ``doc`` key.
    doc: str | None = None

    #: The inputs of the row's failing lanes (name -> array with one entry per failing lane, or
    #: a list of failing cells' records), set by the harness that made the row, so that a
    #: documented cause can be matched against what fails (its signature) rather than against
    #: the topic.  Not a field: it is not part of the JSON, the equality or the table.
    failing_lanes = None

    def __post_init__(self):
        if self.status not in STATUSES:
            raise ValueError(f"unknown status {self.status!r}; choose one of {', '.join(STATUSES)}")

    def to_dict(self) -> dict:
        d = jsonable(asdict(self))
        for key in ("point", "doc"):
            if d[key] is None:
                del d[key]
        return d

    @classmethod
    def from_dict(cls, d: dict) -> "Row":
        return cls(**{k: d.get(k) for k in ("topic", "name", "measured", "expected", "stderr",
                                             "tolerance", "status", "reason")},
                   details=d.get("details") or {}, point=d.get("point"), doc=d.get("doc"))


def format_number(x, digits: int = 4) -> str:
    """A cell of the table: ``digits`` significant digits, "-" for None."""
    if x is None:
        return "-"
    if isinstance(x, str):
        return x
    return f"{x:.{digits}g}"


def header(stderr: bool = False) -> tuple[str, ...]:
    """The column names of :func:`cells` (with a ``stderr`` column when asked)."""
    return ("status", "topic", "name", "measured", "expected") + (("stderr",) if stderr else ()) \
        + ("tolerance",)


def cells(row: Row, digits: int = 4, stderr: bool = False) -> tuple[str, ...]:
    """A row's cells under :func:`header`: numbers to ``digits`` significant digits, the
    expected value prefixed by ``≤``/``≥`` for a one-sided ``details["relation"]``."""
    prefix = RELATION_PREFIX[row.details.get("relation", "==")]
    expected = format_number(row.expected, digits)
    return ((row.status, row.topic, row.name, format_number(row.measured, digits),
             prefix + expected if row.expected is not None else expected)
            + ((format_number(row.stderr, digits),) if stderr else ())
            + (format_number(row.tolerance, digits),))


def table(rows: list[Row], digits: int = 4, stderr: bool = False, reasons: bool = True) -> str:
    """Rows as aligned plain text, one line each (:func:`cells`), each row's reason below it
    (``reasons``)."""
    head = header(stderr)
    body = [cells(r, digits, stderr) for r in rows]
    widths = [max(len(str(x)) for x in col) for col in zip(head, *body)] if body else \
        [len(h) for h in head]
    lines = ["  ".join(str(x).ljust(w) for x, w in zip(head, widths)).rstrip()]
    for r, line in zip(rows, body):
        lines.append("  ".join(str(x).ljust(w) for x, w in zip(line, widths)).rstrip())
        if reasons and r.reason:
            lines.append(" " * (widths[0] + 2) + r.reason)
        if reasons and r.status == "fail" and evidence(r):
            lines.append(" " * (widths[0] + 2) + evidence(r))
    return "\n".join(lines)


def point_label(point: dict | None) -> str:
    """A parameter point as text: ``exponent=0, kd=0.5``; ``given`` for the given point."""
    if not point:
        return "given"
    return ", ".join(f"{k}={format_number(v, 6) if isinstance(v, float) else v}"
                     for k, v in point.items())


def table_by_point(rows: list[Row], digits: int = 4) -> str:
    """A sweep's rows grouped by parameter point: one line per point (its verdict counts and
    its worst row: the first failing one, else the first KNOWN one), then the full rows of
    every point with a failing row."""
    points: dict[str, list[Row]] = {}
    for r in rows:
        points.setdefault(point_label(r.point), []).append(r)
    width = max((len(k) for k in points), default=5)
    lines = [f"{'point'.ljust(width)}  pass fail KNOWN skipped advice  worst row"]
    for label, group in points.items():
        count = {s: sum(r.status == s for r in group) for s in STATUSES}
        worst = _worst(group)
        lines.append(f"{label.ljust(width)}  {count['pass']:4d} {count['fail']:4d} "
                     f"{count['KNOWN']:5d} {count['skipped']:7d} {count['advice']:6d}  "
                     + (f"{worst.status} {worst.topic}: {worst.name} "
                        f"({summary(worst, digits)})" if worst else "all pass"))
    for label, group in points.items():
        failing = [r for r in group if r.status == "fail"]
        if failing:
            lines += ["", f"at {label}:", table(failing, digits)]
    return "\n".join(lines)


def summary(row: Row, digits: int = 4) -> str:
    """A row's numbers in words for a one-line summary: ``measured 1.005, expected ≤ 1
    (tolerance 6.919e-05)``; a row whose ``measured`` is a ratio to its tolerance (its reason
    says ``measured = max ... rel_diff / ...``, tolerance 1) says so; a χ² row names its
    p-value, its level and the first reason a cell was rejected for besides its p-value."""
    n = lambda x: format_number(x, digits)   # noqa: E731
    prefix = RELATION_PREFIX[row.details.get("relation", "==")] if row.details else ""
    if row.measured is None:
        return "not measured"
    reason = row.reason or ""
    if "p-value" in row.name:           # a χ² row: its smallest p-value against the level
        problems = [p for c in (row.details or {}).get("cells", []) if isinstance(c, dict)
                    and c.get("status") == "fail" for p in c.get("problems", [])]
        return (f"min p-value {n(row.measured)}, level {n(row.expected)}"
                + (f"; {problems[0]}" if problems else ""))
    if "measured = " in reason and "rel_diff" in reason and row.tolerance == 1:
        return f"max relative error / its tolerance = {n(row.measured)}, must be ≤ 1"
    out = f"measured {n(row.measured)}"
    if row.expected is not None:
        out += f", expected {prefix}{n(row.expected)}"
    if row.tolerance is not None:
        out += f" (tolerance {n(row.tolerance)})"
    return out


def _worst(rows: list[Row]) -> Row | None:
    """The first row of the worst status among ``rows`` (fail, then KNOWN, then advice), None
    if all pass or are skipped."""
    for status in ("fail", "KNOWN", "advice"):
        found = [r for r in rows if r.status == status]
        if found:
            return found[0]
    return None


def evidence(row: Row) -> str:
    """The worst lane of a failing per-lane row in plain numbers (its directions and the
    values the identity compares there, from ``details``), a failing χ² row's worst bin, or ""
    for rows without one."""
    d = row.details or {}
    if "worst_bin" in d:
        return _worst_bin(d["worst_bin"])
    if "worst_wi" not in d:
        return ""

    def vec(v) -> str:
        return "(" + ", ".join(f"{float(x):.6g}" for x in v) + ")"

    parts = [f"wi = {vec(d['worst_wi'])}", f"wo = {vec(d['worst_wo'])}"]
    parts += [f"{k} = {float(v):.6g}" for k, v in d.items()
              if isinstance(v, (int, float)) and not isinstance(v, bool)
              and k not in ("lanes", "nonfinite_dropped") and not k.startswith("box_")]
    rel = d.get("rel_diff")
    if isinstance(rel, (int, float)) and isinstance(row.measured, (int, float)) and row.measured:
        # measured is rel_diff / the lane's tolerance (round-off + sensitivity)
        parts.append(f"held to a relative tolerance of {rel / row.measured:.3g} there")
    return "worst lane: " + ", ".join(parts)


def _worst_bin(b: dict) -> str:
    """A failing χ² row's worst bin (``details["worst_bin"]``) in plain numbers."""
    def span(key) -> str:
        lo, hi = b[key]
        return f"{float(lo):.1f}° to {float(hi):.1f}°"

    r = b.get("residual")
    r = float(r) if isinstance(r, (int, float)) else float("nan")
    return (f"worst bin: at θ_i = {float(b['theta_i_deg']):.1f}°, φ_i = {float(b['phi_i']):.2f} "
            f"(p = {float(b['p_value']):.3g}), θ_o {span('theta_o_deg')}, φ_o {span('phi_o_deg')}:"
            f" observed {float(b['observed']):.6g}, expected {float(b['expected']):.6g}, "
            + (f"residual {r:+.3g}" if math.isfinite(r) else "pooled (no residual of its own)"))


@dataclass
class Report:
    """The rows of one run (one BSDF's validation, one ``phonglab check``) with ``meta``."""

    meta: dict
    rows: list[Row] = field(default_factory=list)

    @property
    def passed(self) -> bool:
        """True when no row has status ``fail`` (``KNOWN`` and ``skipped`` rows are allowed)."""
        return not self.failing

    @property
    def failing(self) -> list[Row]:
        return [r for r in self.rows if r.status == "fail"]

    @property
    def not_covered(self) -> list[str]:
        """The applicable topics that judged nothing (``meta["not_covered"]``, set by the
        validator: :func:`phonglab.validate.core.not_covered`); [] when it did not say."""
        return list(self.meta.get("not_covered") or [])

    def to_dict(self) -> dict:
        return {"meta": jsonable(self.meta), "results": [r.to_dict() for r in self.rows]}

    def to_json(self, indent: int | None = 1) -> str:
        return json.dumps(self.to_dict(), indent=indent)

    @classmethod
    def from_dict(cls, d: dict) -> "Report":
        return cls(meta=dict(d.get("meta") or {}), rows=[Row.from_dict(r) for r in d["results"]])

    def table(self, rows: list[Row] | None = None, **options) -> str:
        """:func:`table` of ``rows`` (all rows by default); ``options`` as there."""
        return table(self.rows if rows is None else rows, **options)
