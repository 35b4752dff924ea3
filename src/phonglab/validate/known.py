r"""Documented causes of failing rows, and the rule that makes a failing row KNOWN.

A :class:`Known` is a cause with its *signature*: the rows it names, the region of inputs it
explains (the failing lanes inside it) and the parameter values it holds at.  A failing row
becomes KNOWN (same tolerance, still reported) only when every one of its failing lanes lies in
the signature of a cause that names it (:func:`mark_known`); a lane outside every signature
keeps the row a fail and says how many lie outside and where the first is, so a finding never
hides a new failure of its topic.  The conformance tables' findings become such causes
(:meth:`phonglab.validate.conformance.Finding.known`); :func:`phonglab.validate.core.run`
applies the rule to every run, and :mod:`.builtin` the same rule to a wrapper's inherited rows
(:func:`covered_by`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..verdict import Row

__all__ = ["Known", "at_text", "covered_by", "known_entries", "mark_known"]


@dataclass(frozen=True)
class Known:
    """A documented cause of failing rows, matched by its signature, never by topic alone.

    ``rows``: the names of the rows it explains (() -- every row of its topic); ``region``: the
    failing lanes it explains (an object with ``covers(row)`` -> one boolean per failing lane
    or None, and ``text``; :mod:`phonglab.validate.bsdf.signatures`), None for all of them.
    A plain string in ``known`` is a cause with neither: what a user writes by hand for a
    topic they have judged as a whole.
    """

    cause: str
    rows: tuple[str, ...] = ()
    region: Any = None
    key: str = ""                  #: the finding's id, if it is one
    #: parameter values the cause holds at ((name, value) or (name, (lo, hi)), ...): it
    #: explains nothing at a point where a named parameter has another value (outside
    #: [lo, hi]) or none (() -- at every point)
    at: tuple[tuple[str, Any], ...] = ()

    def holds_at(self, values: dict | None) -> bool:
        """Whether the plugin's parameter ``values`` (name -> float) meet :attr:`at`."""
        for name, v in self.at:
            got = (values or {}).get(name)
            if not isinstance(got, (int, float)):
                return False
            lo, hi = v if isinstance(v, tuple) else (v, v)
            slack = 1e-6 * max(1.0, abs(lo), abs(hi))
            if not lo - slack <= got <= hi + slack:
                return False
        return True

    def names(self, row: Row) -> bool:
        """Whether the cause names ``row`` (a parameter row ``nested.eta.value`` matches
        ``eta.value``: the same parameter of a nested plugin)."""
        return not self.rows or any(row.name == n or row.name.endswith("." + n)
                                    for n in self.rows)

    def describe(self) -> str:
        """One line for the report's meta: the cause, and the signature when it has one."""
        where = []
        if self.rows:
            where.append("rows " + ", ".join(repr(r) for r in self.rows))
        if self.region is not None:
            where.append(self.region.text)
        if self.at:
            where.append("at " + at_text(self.at))
        return self.cause + (f" [signature: {'; '.join(where)}]" if where else "")


def at_text(at) -> str:
    """``int_ior in [2, 3], diffuse_reflectance = 1``: the parameter values a cause holds at."""
    return ", ".join(f"{n} in [{v[0]:g}, {v[1]:g}]" if isinstance(v, tuple) else f"{n} = {v:g}"
                     for n, v in at)


def known_entries(value) -> tuple[Known, ...]:
    """A ``known`` value (a cause string, a :class:`Known`, or a sequence of them) as Knowns."""
    if value is None:
        return ()
    if isinstance(value, (str, Known)):
        value = (value,)
    return tuple(Known(v) if isinstance(v, str) else v for v in value)


def _failing_count(row: Row) -> int:
    lanes = row.failing_lanes
    return len(next(iter(lanes.values()))) if lanes else 1


def mark_known(rows: list[Row], known, values: dict | None = None) -> None:
    """A failing row whose every failing lane lies in the signature of a documented cause that
    names it (and holds at the plugin's parameter ``values``) becomes KNOWN, its reason
    prefixed by the cause(s); a failing lane outside every such signature keeps the row a
    fail, and its reason and details say how many lanes lie outside and where the first one
    is (a new failure hides behind no old finding)."""
    for r in rows:
        causes = [k for k in known_entries((known or {}).get(r.topic))
                  if k.names(r) and k.holds_at(values)]
        if r.status != "fail" or not causes:
            continue
        n = _failing_count(r)
        covered, used = _coverage(r, causes)
        if covered.all():
            r.status = "KNOWN"
            r.reason = f"{'; '.join(k.cause for k in used)} ({r.reason})"
            keys = [k.key for k in used if k.key]
            if keys:
                r.details["known_by"] = keys
            continue
        outside = int(n - covered.sum())
        texts = "; ".join(dict.fromkeys(k.region.text for k in causes if k.region is not None))
        r.reason += (f"; {outside} of {n} failing lanes lie outside every documented signature "
                     f"({texts})")
        first = int(np.flatnonzero(~covered)[0])
        r.details["outside_signature"] = {
            "lanes": outside, "of": n, "findings": [k.key or k.cause[:80] for k in causes],
            "first": {k: _lane_value(v, first) for k, v in (r.failing_lanes or {}).items()}}


def _coverage(row: Row, causes) -> tuple[np.ndarray, list]:
    """Which failing lanes of ``row`` lie in the signature of one of ``causes``, and the
    causes that cover any."""
    n = _failing_count(row)
    covered = np.zeros(n, bool)
    used = []
    for k in causes:
        mask = np.ones(n, bool) if k.region is None else k.region.covers(row)
        if mask is None or len(mask) != n or not np.any(mask):
            continue
        covered |= np.asarray(mask, bool)
        used.append(k)
    return covered, used


def covered_by(row: Row, causes) -> tuple[bool, list]:
    """(every failing lane of ``row`` lies in a signature of ``causes``, the causes used): the
    rule :func:`mark_known` applies."""
    covered, used = _coverage(row, causes)
    return bool(covered.all()), used


def _lane_value(values, i):
    v = values[i]
    if isinstance(v, dict):          # a χ² cell's record: its incidence only
        return {k: v[k] for k in ("theta_deg", "phi", "p_value") if k in v}
    return np.asarray(v).tolist()
