"""What a job costs on phonglab.parallel beyond its own work, serially and on a LocalCluster.

Runs ``--jobs`` empty jobs (``time.sleep(0)``) through a :class:`phonglab.parallel.Runner`,
serially and on a LocalCluster of ``--workers`` processes, ``--repeats`` times each, and
prints (and writes with ``--out``) as JSON:

* ``start_s``: the time to start the LocalCluster and prepare its workers (the worker
  plugin imports Mitsuba, sets the variant, registers the plugins);
* ``per_job_ms``: (wall time of the batch) / jobs, median over repeats: the scheduling,
  pickling and round-trip cost of one job, what a job must outweigh to be worth sending;
* for a bench folder given with ``--bench`` (its ``run.json``), the job-time figures per part
  and the time those jobs would take on N workers, bounded below by the longest job and by
  (sum of job times)/N: T_N ≈ max(max_job, sum/N) + per_job · count / N.

Run: ``.venv/bin/python scripts/parallel_overhead.py [--workers 2] [--jobs 400] [--bench out/bench-quick]``
(docs/cluster.md quotes its figures).
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

from phonglab.parallel import Job, Runner


def batch_ms(runner: Runner, jobs: int) -> float:
    """Milliseconds per empty job of one batch of ``jobs`` on ``runner``."""
    t0 = time.perf_counter()
    runner.run([Job(time.sleep, (0,), key=k) for k in range(jobs)])
    return (time.perf_counter() - t0) / jobs * 1e3


def on_n(parts: dict, per_job_ms: float, n_values=(1, 2, 4, 8, 16, 64)) -> dict:
    """Expected seconds of each part's jobs on N workers (lower bounds: the longest job, sum/N)."""
    out = {}
    for part, j in parts.items():
        if not j.get("count"):
            continue
        out[part] = {n: round(max(j["max_s"], j["sum_s"] / n) + per_job_ms / 1e3 * j["count"] / n, 2)
                     for n in n_values}
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--jobs", type=int, default=400)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--bench", type=Path, default=None, help="a bench output folder (run.json)")
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    result = {}
    with Runner(progress=False) as serial:
        batch_ms(serial, 10)
        result["serial_per_job_ms"] = round(statistics.median(
            batch_ms(serial, args.jobs) for _ in range(args.repeats)), 4)
    t0 = time.perf_counter()
    with Runner(args.workers, progress=False) as local:
        result["local_start_s"] = round(time.perf_counter() - t0, 2)
        batch_ms(local, 10)
        times = [batch_ms(local, args.jobs) for _ in range(args.repeats)]
    result.update(workers=args.workers, jobs=args.jobs,
                  local_per_job_ms=round(statistics.median(times), 3),
                  local_per_job_ms_spread=[round(min(times), 3), round(max(times), 3)])
    if args.bench:
        run = json.loads((args.bench / "run.json").read_text())
        parts = run.get("execution", {}).get("jobs", {})
        result["bench"] = {"where": run["execution"]["where"], "parts": parts,
                           "seconds_on_n_workers": on_n(parts, result["local_per_job_ms"])}
    text = json.dumps(result, indent=2)
    print(text)
    if args.out:
        args.out.write_text(text + "\n")


if __name__ == "__main__":
    main()
