"""Wall time of ``phonglab validate BSDF`` (default and --quick), as a user sees it.

Each run is a fresh ``phonglab validate`` process (start-up, Mitsuba import, kernel compilation
-- Dr.Jit's on-disk kernel cache is warm after the first repeat -- and every topic); the two
modes of one BSDF are timed alternately, the median and the range of ``--repeats`` runs printed
as a Markdown table.  Targets: default ≤ 60 s, --quick ≤ 10 s per BSDF on 2 cores.

    python scripts/validate_timing.py [--repeats 3] [--json docs/bench/validate.json] [BSDF ...]

``--json`` writes the rows for BENCHMARKS.md (``bench/report.py``'s validate section).
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

DEFAULT_BSDFS = ["diffuse", "lambert", "phong", "roughplastic"]


def wall(argv) -> tuple[float, int]:
    t0 = time.perf_counter()
    rc = subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL).returncode
    return time.perf_counter() - t0, rc


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("bsdfs", nargs="*", default=DEFAULT_BSDFS)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--json", metavar="PATH", help="also write the rows as JSON")
    args = ap.parse_args()
    rows = []
    exe = [sys.executable, "-m", "phonglab.cli"]
    print("| BSDF | default (s) median [min, max] | --quick (s) median [min, max] | exit codes |")
    print("|---|---|---|---|")
    for name in args.bsdfs:
        times = {"default": [], "quick": []}
        codes = set()
        for _ in range(args.repeats):
            for mode, extra in (("default", []), ("quick", ["--quick"])):
                t, rc = wall(exe + ["validate", name] + extra)
                times[mode].append(t)
                codes.add(rc)
        cells = [f"{statistics.median(v):.1f} [{min(v):.1f}, {max(v):.1f}]"
                 for v in times.values()]
        print(f"| {name} | {cells[0]} | {cells[1]} | {sorted(codes)} |", flush=True)
        rows.append({"bsdf": name, "repeats": args.repeats, "exit_codes": sorted(codes),
                     **{f"{m}_seconds": v for m, v in times.items()}})
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
