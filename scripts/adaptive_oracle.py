"""The bench's adaptive oracle rows at 128², 256² and 512², and where adaptive's time goes.

``phonglab.bench.adaptive_oracle`` has the method (its docstring).  Two phases, in order:

1. **prepare** (not timed: may run while the machine is busy): per size, smallest first, each
   scene's full-depth reference (rendered into the reference cache if missing, its spp by
   ``adaptive_oracle.reference_spp``) and its sample and time oracles; kept in
   ``--prepared`` so an interrupted run resumes;
2. **timed**: waits until the 1-minute load average is below 1.5 (a minute at a time, at most
   ``--max-wait``, 20 min), then every row in one go (a warm-up seed, then ``--seeds`` paired
   seeds), and writes ``--json`` with the load averages at its start and end.

    python scripts/adaptive_oracle.py [--scales 1 2 4] [--seeds 3] [--prepare-only]
        [--json docs/bench/adaptive_oracle.json]

BENCHMARKS.md shows the JSON (``adaptive_oracle.report_section``) when ``make bench``
regenerates it.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from datetime import datetime, timezone
from pathlib import Path

from phonglab.bench import adaptive_oracle as ao
from phonglab.bench.config import VARIANT, Config
from phonglab.engine.outputs import write_json
from phonglab.runtime import set_variant


def log(msg: str) -> None:
    print(f"[{datetime.now():%H:%M:%S}] {msg}", file=sys.stderr, flush=True)


def prepare(scales, specs, path: Path) -> dict:
    """Phase 1: every (scene, scale)'s reference and oracles, resumed from ``path``."""
    done = json.loads(path.read_text()) if path.is_file() else {}
    for scale in sorted(scales):
        for name, (target, params) in specs.items():
            key = f"{name}@{scale}"
            if key in done:
                continue
            smaller = done.get(f"{name}@{scale // 2}")
            spp = (ao.ORACLE_REFERENCE_SPP if scale == 1 or smaller is None else
                   ao.reference_spp(smaller["reference_noise"], smaller["reference_spp"], target))
            p = ao.scaled_params(params, scale)
            log(f"prepare {name} {ao.size_label(p)}: reference {spp} spp, oracle maps")
            done[key] = dict(ao.prepare_row(name, target, p, spp), scale=scale)
            r = done[key]
            log(f"  reference noise {r['reference_noise_e']:.2f} E (rendered in "
                f"{r['reference_render_seconds']:.0f} s), oracle {r['oracle']:.2f}x, time oracle "
                f"{r['oracle_time']:.2f}x, {r['prepare_seconds']:.0f} s")
            write_json(path, done, indent=1)
    return done


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scales", type=int, nargs="+", default=list(ao.SCALES))
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--scenes", nargs="*", help="only these of the bench's oracle scenes")
    ap.add_argument("--quick", action="store_true",
                    help="the bench's --quick oracle scenes (32²: a smoke run, seconds)")
    ap.add_argument("--prepared", type=Path, default=Path("out/adaptive_oracle/prepared.json"))
    ap.add_argument("--prepare-only", action="store_true")
    ap.add_argument("--max-wait", type=float, default=1200.0, metavar="S",
                    help="most seconds to wait for a quiet machine before the timed run")
    ap.add_argument("--json", type=Path, default=Path("docs/bench") / ao.JSON_NAME)
    args = ap.parse_args()
    specs = Config(quick=args.quick).adaptive_oracle_scenes
    unknown = sorted(set(args.scenes or ()) - set(specs))
    if unknown:
        print(f"adaptive_oracle: not an oracle scene of the bench: {', '.join(unknown)}",
              file=sys.stderr)
        return 2
    if args.scenes:
        specs = {k: v for k, v in specs.items() if k in args.scenes}
    if any(s < 1 or s & (s - 1) for s in args.scales):
        print("adaptive_oracle: --scales must be powers of two (1 2 4)", file=sys.stderr)
        return 2
    set_variant(VARIANT)
    t0 = time.perf_counter()
    done = prepare(args.scales, specs, args.prepared)
    prepare_seconds = time.perf_counter() - t0
    if args.prepare_only:
        return 0
    quiet = ao.wait_for_quiet(most=args.max_wait, log=log)
    log(f"timed run: load average {quiet['load']} after {quiet['waited_s']:.0f} s of waiting")
    t1 = time.perf_counter()
    rows = []
    for scale in sorted(args.scales):
        for name in specs:
            row = ao.timed_row(done[f"{name}@{scale}"], args.seeds)
            rows.append(row)
            log(f"{name} {ao.size_label(row['params'])}: achieved {row['achieved']['median']:.2f}x "
                f"of time oracle {row['oracle_time']:.2f}x ({row['share_time']:.2f}), factors "
                + ", ".join(f"{k} {v:.2f}" for k, v in row["factors"].items()))
    from phonglab.bench.run import machine_info
    meta = {"date": datetime.now(timezone.utc).strftime("%Y-%m-%d"), "seeds": args.seeds,
            "scales": sorted(args.scales), "cores": os.cpu_count(),
            "load_start": quiet["load"], "waited_s": quiet["waited_s"],
            "load_end": [round(x, 2) for x in os.getloadavg()],
            "timed_seconds": round(time.perf_counter() - t1, 1),
            "prepare_seconds": round(prepare_seconds, 1),
            "prepare_seconds_all": round(sum(done[f"{r['scene']}@{r['scale']}"]["prepare_seconds"]
                                             for r in rows), 1),
            "machine": machine_info()}
    write_json(args.json, {"meta": meta, "rows": rows}, indent=1, end="\n")
    log(f"wrote {args.json} (timed run {meta['timed_seconds'] / 60:.1f} min, load "
        f"{meta['load_start'][0]} → {meta['load_end'][0]})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
