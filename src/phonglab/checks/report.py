"""Running the checks and reporting their rows: the registry, the text table and the JSON file."""

from __future__ import annotations

import json
import math
import time
from pathlib import Path
from typing import Callable

import numpy as np

from .. import registration
from ..errors import PhonglabError
from . import CHECK_NAMES
from .common import CheckResult, Config, jsonable
from .constancy import check_constancy
from .energy import check_energy
from .reflection import check_reflection
from .sanity import check_sanity
from .scene import check_scene
from .snell import check_snell

#: Each check by name; :data:`phonglab.checks.CHECK_NAMES` gives the order of the table.
CHECKS: dict[str, Callable[[Config], list[CheckResult]]] = {
    "energy": check_energy,
    "reflection": check_reflection,
    "scene": check_scene,
    "constancy": check_constancy,
    "snell": check_snell,
    "sanity": check_sanity,
}


def run_checks(names=None, cfg: Config | None = None,
               on_check: Callable[[str], None] | None = None) -> list[CheckResult]:
    """Run the named checks (all by default) in the order of :data:`CHECK_NAMES`."""
    cfg = cfg or Config()
    names = list(names or CHECK_NAMES)
    unknown = [n for n in names if n not in CHECKS]
    if unknown:
        raise PhonglabError(f"unknown check {', '.join(map(repr, unknown))}; choose from "
                            f"{', '.join(CHECK_NAMES)}.")
    registration.register()
    results: list[CheckResult] = []
    for name in [n for n in CHECK_NAMES if n in names]:
        if on_check:
            on_check(name)
        t0 = time.perf_counter()
        rows = CHECKS[name](cfg)
        for r in rows:
            r.details.setdefault("check_seconds", round(time.perf_counter() - t0, 2))
        results.extend(rows)
    return results


def format_table(results: list[CheckResult]) -> str:
    """The rows as a fixed-width text table."""
    head = ("check", "row", "measured", "expected", "stderr", "tol", "status")
    lines = []
    for r in results:
        rel = {"==": "", "<=": "≤ ", ">=": "≥ "}[r.relation]
        lines.append((r.check, r.name, _fmt(r.measured), rel + _fmt(r.expected), _fmt(r.stderr),
                      _fmt(r.tolerance), r.status))
    widths = [max(len(h), *(len(line[i]) for line in lines)) if lines else len(h)
              for i, h in enumerate(head)]
    out = ["  ".join(h.ljust(w) for h, w in zip(head, widths)),
           "  ".join("-" * w for w in widths)]
    for line in lines:
        out.append("  ".join(c.ljust(w) for c, w in zip(line, widths)))
    return "\n".join(out)


def _fmt(x: float) -> str:
    if isinstance(x, (int, np.integer)) or (isinstance(x, float) and x.is_integer()
                                            and abs(x) < 1e6):
        return f"{int(x)}"
    if not math.isfinite(x):
        return str(x)
    return f"{x:.6g}"


def write_json(path: str | Path, results: list[CheckResult], meta: dict | None = None) -> Path:
    """The rows (every field, with ``status``) and ``meta`` as JSON at ``path``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    data = {"meta": jsonable(meta or {}), "results": [r.to_dict() for r in results]}
    path.write_text(json.dumps(data, indent=2, ensure_ascii=False))
    return path
