"""Wall time of ``phonglab validate BSDF`` (default and --quick), as a user sees it.

Each run is a fresh ``phonglab validate`` process timed by :mod:`phonglab.bench.timing`
(start-up, Mitsuba import, kernel compilation -- Dr.Jit's on-disk kernel cache is warm after
the first repeat -- and every topic); the two modes of one BSDF are timed alternately, the
median and the range of ``--repeats`` runs printed as a Markdown table.  Targets: default
≤ 60 s, --quick ≤ 10 s per BSDF on 2 cores.

    python scripts/validate_timing.py [--repeats 3] [--json docs/bench/validate.json] [BSDF ...]

``--json`` writes the rows for BENCHMARKS.md (``bench/report.py``'s validate section).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from phonglab.bench.timing import PHONGLAB, run_child, spread
from phonglab.engine.outputs import write_json

DEFAULT_BSDFS = ["diffuse", "lambert", "phong", "roughplastic"]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("bsdfs", nargs="*", default=DEFAULT_BSDFS)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--json", metavar="PATH", help="also write the rows as JSON")
    args = ap.parse_args()
    rows = []
    print("| BSDF | default (s) median [min, max] | --quick (s) median [min, max] | exit codes |")
    print("|---|---|---|---|")
    for name in args.bsdfs:
        times = {"default": [], "quick": []}
        codes = set()
        for _ in range(args.repeats):
            for mode, extra in (("default", []), ("quick", ["--quick"])):
                run = run_child(PHONGLAB + ["validate", name] + extra, quiet=True, accept=None)
                times[mode].append(run.seconds)
                codes.add(run.returncode)
        cells = [f"{s['median']:.1f} [{s['spread'][0]:.1f}, {s['spread'][1]:.1f}]"
                 for s in (spread(v, None) for v in times.values())]
        print(f"| {name} | {cells[0]} | {cells[1]} | {sorted(codes)} |", flush=True)
        rows.append({"bsdf": name, "repeats": args.repeats, "exit_codes": sorted(codes),
                     **{f"{m}_seconds": v for m, v in times.items()}})
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        write_json(args.json, rows, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
