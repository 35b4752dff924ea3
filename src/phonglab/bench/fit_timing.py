"""The speed of ``phonglab fit``: the issue's example command timed as a user runs it.

``python -m phonglab.bench.fit_timing --out docs/bench/fit.json`` (run by ``make bench``)
starts ``phonglab fit roughconductor --set alpha=0.2`` as a fresh process ``repeats`` times
(:mod:`.timing`: so every run pays the import, the variant set-up and the JIT compilation)
and records the median, the minimum and the maximum wall time, the median CPU time of the
child, and the load average around the runs; BENCHMARKS.md's fitting section reads it.  The
target is under a minute on two cores.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
from pathlib import Path

from .timing import PHONGLAB, run_repeated, spread
from ..engine.outputs import write_json

#: The command the issue times, and its limit in seconds.
COMMAND = ["fit", "roughconductor", "--set", "alpha=0.2"]
LIMIT_S = 60.0


def time_command(repeats: int = 5, args: list[str] = COMMAND) -> dict:
    """Wall and CPU seconds of ``python -m phonglab.cli ARGS``, fresh process each time."""
    load_before = os.getloadavg()[0]
    runs = run_repeated(PHONGLAB + list(args), repeats)
    wall = spread([r.seconds for r in runs], 3)
    return {"command": "phonglab " + " ".join(args), "repeats": repeats,
            "wall_median_s": wall["median"], "wall_min_s": wall["spread"][0],
            "wall_max_s": wall["spread"][1],
            "cpu_median_s": round(statistics.median(r.cpu_seconds for r in runs), 3),
            "cores": os.cpu_count(), "load_before": round(load_before, 2),
            "load_after": round(os.getloadavg()[0], 2), "limit_s": LIMIT_S,
            "met": statistics.median(r.seconds for r in runs) < LIMIT_S}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="JSON file to write")
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args(argv)
    record = time_command(args.repeats)
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    write_json(args.out, record, indent=1, end="\n")
    print(json.dumps(record))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
