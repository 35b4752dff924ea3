"""What BENCHMARKS.md is written from: a bench run folder read once (:class:`RunData`: its
run.json, CSV logs and the ratios derived from them, :func:`part_record` for a part's JSON),
and the two number formats every section uses."""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .analysis import efficiency_ratios, mis_ratios, ratio_summary
from .csvlog import open_log


def fmt_met(ok: bool | None) -> str:
    return "n/a" if ok is None else ("**met**" if ok else "**not met**")


def fmt_g(x: float | None, digits: int = 3) -> str:
    return "n/a" if x is None or not math.isfinite(x) else f"{x:.{digits}g}"


@dataclass
class RunData:
    """Everything a report reads from a run folder, and the figures derived from it."""

    out: Path
    rel: str                                   #: the run folder relative to the report
    run: dict[str, Any]
    results: list[dict]
    stab: list[dict]
    ratios: list[dict]
    jit: list[dict]
    quick: dict[str, Any] | None
    rs: dict = field(default_factory=dict)     #: ratio_summary
    eff: dict = field(default_factory=dict)    #: efficiency_ratios
    mis: dict = field(default_factory=dict)    #: mis_ratios
    mis_opt: dict = field(default_factory=dict)  #: mis_ratios of mis_optimal

    @classmethod
    def read(cls, out: Path, md_path: Path, quick_run: Path | None = None) -> "RunData":
        run = json.loads((out / "run.json").read_text()) if (out / "run.json").is_file() else {}
        # the quick run's record: the file given, else the one the full run kept (run.py), so
        # that BENCHMARKS.md can be re-rendered from docs/bench alone
        quick = json.loads(Path(quick_run).read_text()) if quick_run and Path(quick_run).is_file() else (
            run if run.get("mode") == "quick" else run.get("quick_run"))
        data = cls(out=out, rel=os.path.relpath(out, md_path.parent), run=run,
                   results=open_log(out, "results").rows, stab=open_log(out, "stability").rows,
                   ratios=open_log(out, "ratios").rows, jit=open_log(out, "jit").rows, quick=quick)
        data.rs = ratio_summary(data.ratios)
        data.eff = efficiency_ratios(data.results, open_log(out, "cost").rows)
        data.mis = mis_ratios(data.stab)
        data.mis_opt = mis_ratios(data.stab, "mis_optimal")
        return data


def part_record(d: RunData, name: str) -> Any:
    """The parsed JSON file ``name`` in ``d.out`` (the record a bench part wrote), or None
    when that part did not run."""
    path = d.out / name
    return json.loads(path.read_text()) if path.is_file() else None
