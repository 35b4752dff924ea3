"""``phonglab bench``: speed against accuracy sweeps, charts, stability map, BENCHMARKS.md."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..bench.config import PARTS
from ..parallel import add_arguments, runner_from_args


def add_parser(sub) -> None:
    p = sub.add_parser(
        "bench", help="error-versus-time sweeps, stability map and charts (CSV + PNG)",
        description="Run the estimator, stability, render, variant and render-time-ratio sweeps. "
                    "Rows are written to CSV as they finish; a re-run resumes (skips rows already "
                    "there) unless --fresh. Charts are PNG files beside the CSVs.",
        epilog="examples:\n  phonglab bench --quick --out out/bench-quick\n"
               "  phonglab bench --fresh --out docs/bench --markdown BENCHMARKS.md\n"
               "  phonglab bench --only stability --out out/bench\n"
               "  phonglab bench --quick --workers 2\n"
               "  phonglab bench --scheduler tcp://10.0.0.5:8786",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--quick", action="store_true", help="small sizes: finishes in < 3 minutes on 2 cores")
    p.add_argument("--out", default="out/bench", help="output folder for CSV/PNG (default out/bench)")
    p.add_argument("--fresh", action="store_true", help="delete earlier results in --out first")
    p.add_argument("--markdown", default=None, help="also write this Markdown report (BENCHMARKS.md)")
    p.add_argument("--only", nargs="+", choices=PARTS, default=list(PARTS), metavar="PART",
                   help=f"run only these parts ({', '.join(PARTS)})")
    p.add_argument("--quick-run", default=None,
                   help="run.json of a --quick run, whose wall time the report quotes")
    p.add_argument("--cache", default=None,
                   help="reference-image cache folder (default $PHONGLAB_CACHE, else .bench_cache/ "
                        "in a checkout, ~/.cache/phonglab when installed)")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    add_arguments(p)
    p.set_defaults(func=run)


def run(args) -> int:
    from ..bench.run import run_bench  # lazy: the sweeps load scipy, matplotlib and Mitsuba (~1.5 s)
    from ..engine.outputs import check_input_file, check_output_file, check_output_folder

    # Every path before the first sweep: the report and the rows must have somewhere to go.
    check_output_folder(args.out, "bench output folder (--out)")
    if args.quick_run is not None:
        check_input_file(args.quick_run, "run.json of a --quick run (--quick-run)")
    if args.markdown is not None:
        check_output_file(args.markdown, "Markdown report (--markdown)",
                          [(args.quick_run, "run.json of a --quick run (--quick-run)")])
    if args.cache is not None:
        check_output_folder(args.cache, "reference cache (--cache)")
    rec = run_bench(Path(args.out), quick=args.quick, fresh=args.fresh,
                    markdown=Path(args.markdown) if args.markdown is not None else None, parts=args.only,
                    cache=Path(args.cache) if args.cache is not None else None,
                    progress=not args.no_progress,
                    quick_run=Path(args.quick_run) if args.quick_run is not None else None,
                    runner=runner_from_args(args))
    print(f"bench ({rec['mode']}) finished in {rec['seconds']:.1f} s ({rec['execution']['where']}); "
          f"results in {args.out}/")
    return 0
