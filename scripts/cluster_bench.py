r"""Serial against a local Dask cluster, in one run: wall times, per-job overhead, time on N machines.

Writes ``docs/bench/cluster.json`` (``make bench-cluster``), which
:func:`phonglab.bench.report.cluster_section` renders into BENCHMARKS.md.  In one run:

* **wall time of whole commands**, fresh processes, serial and ``--workers W`` alternating
  (the serial one first in even rounds, the cluster first in odd ones), each into its own
  output folder under ``--work``: ``phonglab bench --quick --fresh`` and
  ``phonglab validate --all-builtins --quick --json``.  Rounds repeat while the next pair is
  expected to fit in ``--budget`` seconds (at least one round); medians and [min, max].
* **same results**: each pair's validate JSON files are compared with their timing fields
  removed: the keys in :data:`TIMING_KEYS` at any depth, of the ``cost`` topic's rows
  (a timing: :data:`TIMING_TOPICS`) only topic, name and status are kept, and durations in
  text (``mi.chi2``'s "(25.56 ms)" in the chi2 rows' messages: :data:`TIMING_TEXT`) are masked.
* **per-job overhead**: ``--jobs`` empty jobs (``time.sleep(0)``) through a
  :class:`phonglab.parallel.Runner`, serially and on a LocalCluster of W processes,
  ``--overhead-repeats`` batches each: (wall time of a batch) / jobs, median and spread,
  and the LocalCluster's start (its processes importing Dask, Mitsuba and phonglab, the
  worker plugin preparing them).
* **expected time on N machines** from the serial runs' job-time distributions (the bench's
  ``run.json`` ``execution.jobs`` per part; validate's per-case ``wall_seconds``), medians
  over rounds.  With C jobs whose times sum to S, the longest M, and per-job overhead o,

      T_N ≈ max(M, S/N) + o·C/N

  per batch of jobs (each bench part is one batch: the parts run one after the other), plus
  the time the command spends outside jobs (start-up, the bench's ``jit`` subprocess,
  charts), which does not spread: ``here = serial wall − Σ S``.  Serial job times are the
  time of a job with the whole machine, as on a cluster with one worker per machine of this
  kind; the longest job bounds T_N from below whatever N.

Run: ``.venv/bin/python scripts/cluster_bench.py [--workers 2] [--budget 360] [--out docs/bench/cluster.json]``
"""

from __future__ import annotations

import argparse
import json
import os
import re
import statistics
import sys
import time
from pathlib import Path

from phonglab.bench.timing import ChildFailed, run_child, spread
from phonglab.parallel import Job, Runner
from phonglab.engine.outputs import write_json

#: Machines the expected time is computed for.
N_VALUES = (1, 2, 4, 8, 16, 64)
#: Keys of a validate report that are wall times (at any depth); ``profile`` is a run's time
#: per topic split into compilation, execution and the rest, with its kernel counts (a
#: worker's own kernel cache compiles what the serial run's had).
TIMING_KEYS = ("seconds", "topic_seconds", "wall_seconds", "profile")
#: Topics whose rows are timings: only their topic, name and status are compared.
TIMING_TOPICS = ("cost",)
#: Durations inside text: ``mi.chi2`` writes "Histogram sum = 1.000000 (25.56 ms)" into the
#: chi2 rows' ``messages``; such a "(<number> ms)" or "(<number> s)" is replaced by "(time)".
TIMING_TEXT = re.compile(r"\(\d+(?:\.\d+)? m?s\)")
BIN = Path(sys.executable).parent
ROOT = Path(__file__).resolve().parents[1]


def batch_ms(runner: Runner, jobs: int) -> float:
    """Milliseconds per empty job of one batch of ``jobs`` on ``runner``."""
    t0 = time.perf_counter()
    runner.run([Job(time.sleep, (0,), key=k) for k in range(jobs)])
    return (time.perf_counter() - t0) / jobs * 1e3


def overhead(workers: int, jobs: int, repeats: int) -> dict:
    """Per-job cost of empty jobs serially and on a LocalCluster of ``workers``; its start."""
    with Runner(progress=False) as serial:
        batch_ms(serial, 10)
        serial_ms = [batch_ms(serial, jobs) for _ in range(repeats)]
    t0 = time.perf_counter()
    with Runner(workers, progress=False) as local:
        start_s = time.perf_counter() - t0
        batch_ms(local, 10)
        local_ms = [batch_ms(local, jobs) for _ in range(repeats)]
    return {"jobs": jobs, "repeats": repeats, "serial_per_job_ms": spread(serial_ms, 4),
            "local_per_job_ms": spread(local_ms), "local_start_s": round(start_s, 2)}


def without_timings(x):
    """A validate JSON without its timing fields (:data:`TIMING_KEYS`, :data:`TIMING_TOPICS`,
    :data:`TIMING_TEXT`)."""
    if isinstance(x, dict):
        if x.get("topic") in TIMING_TOPICS:
            return {k: x.get(k) for k in ("topic", "name", "status")}
        return {k: without_timings(v) for k, v in x.items() if k not in TIMING_KEYS}
    if isinstance(x, list):
        return [without_timings(v) for v in x]
    if isinstance(x, str):
        return TIMING_TEXT.sub("(time)", x)
    return x


def timed(cmd: list[str], log: Path) -> float:
    """Wall seconds of ``cmd`` as a fresh process (output to ``log``); exit 0 or 1 accepted
    (validate exits 1 when a row fails: a result, not a fault)."""
    try:
        return run_child(cmd, log=log, cwd=ROOT, accept=(0, 1)).seconds
    except ChildFailed as exc:
        raise SystemExit(str(exc)) from None


def commands(work: Path, workers: int) -> dict:
    """The two commands, serial and on ``workers``: {name: {mode: (argv, output path)}}."""
    out = {}
    for mode, extra in (("serial", []), ("workers", ["--workers", str(workers)])):
        bench_out, vjson = work / f"bench-{mode}", work / f"validate-{mode}.json"
        out.setdefault("bench", {})[mode] = (
            [str(BIN / "phonglab"), "bench", "--quick", "--fresh", "--no-progress",
             "--out", str(bench_out), *extra], bench_out)
        out.setdefault("validate", {})[mode] = (
            [str(BIN / "phonglab"), "validate", "--all-builtins", "--quick", "--json", str(vjson),
             *extra], vjson)
    return out


def job_times(name: str, path: Path) -> dict:
    """The job-time distribution of one finished run: {batch: {count, sum_s, median_s, max_s,
    longest}} (the bench: one batch per part, from run.json; validate: one batch of cases)."""
    if name == "bench":
        parts = json.loads((path / "run.json").read_text())["execution"]["jobs"]
        return {p: dict(j, longest=p) for p, j in parts.items() if j.get("count")}
    cases = {r["meta"]["case"]: r["meta"]["wall_seconds"]
             for r in json.loads(path.read_text())["reports"]}
    t = list(cases.values())
    return {"cases": {"count": len(t), "sum_s": round(sum(t), 3),
                      "median_s": round(statistics.median(t), 4), "max_s": round(max(t), 3),
                      "longest": max(cases, key=cases.get)}}


def one_pair(name: str, modes: dict, order: list[str], work: Path) -> dict:
    """Both modes of one command, in ``order``: wall times, serial job times, same results."""
    wall = {}
    for mode in order:
        argv, _ = modes[mode]
        wall[mode] = timed(argv, work / f"{name}-{mode}.log")
    row = {"order": order, "wall_s": {m: round(s, 2) for m, s in wall.items()},
           "jobs": job_times(name, modes["serial"][1])}
    if name == "validate":
        a, b = (json.loads(modes[m][1].read_text()) for m in ("serial", "workers"))
        row["identical"] = without_timings(a) == without_timings(b)
    return row


def median_jobs(pairs: list[dict]) -> dict:
    """Per batch, the median over rounds of count, sum, median and longest job time."""
    out = {}
    for batch in pairs[0]["jobs"]:
        rows = [p["jobs"][batch] for p in pairs if batch in p["jobs"]]
        out[batch] = {k: round(statistics.median(r[k] for r in rows), 4)
                      for k in ("count", "sum_s", "median_s", "max_s")}
        out[batch]["count"] = int(out[batch]["count"])
        longest = max(rows, key=lambda r: r["max_s"])["longest"]
        out[batch]["longest"] = longest
    return out


def on_n(batches: dict, here_s: float, per_job_ms: float, n_values=N_VALUES) -> dict:
    """Expected seconds on N machines: per batch max(M, S/N) + o·C/N, plus ``here_s``."""
    rows = {b: {str(n): round(max(j["max_s"], j["sum_s"] / n) + per_job_ms / 1e3 * j["count"] / n, 2)
                for n in n_values} for b, j in batches.items()}
    total = {str(n): round(here_s + sum(r[str(n)] for r in rows.values()), 1) for n in n_values}
    longest = max(batches, key=lambda b: batches[b]["max_s"])
    return {"batches": rows, "here_s": round(here_s, 2), "total_s": total,
            "longest_job": {"batch": longest, "job": batches[longest]["longest"],
                            "seconds": batches[longest]["max_s"]},
            # from this N on, the longest batch's S/N is below its longest job
            "bound_from_n": {b: max(1, int(-(-j["sum_s"] // j["max_s"]))) for b, j in batches.items()
                             if j["max_s"] > 0}}


def summarize(name: str, pairs: list[dict], per_job_ms: float) -> dict:
    """One command's record: wall times (median, spread), speed-up, job times, on N machines."""
    serial = [p["wall_s"]["serial"] for p in pairs]
    workers = [p["wall_s"]["workers"] for p in pairs]
    jobs = median_jobs(pairs)
    here = max(0.0, statistics.median(serial) - sum(j["sum_s"] for j in jobs.values()))
    rec = {"rounds": len(pairs), "serial_s": spread(serial, 2), "workers_s": spread(workers, 2),
           "speedup": spread([s / w for s, w in zip(serial, workers)], 3),
           "jobs": jobs, "on_n": on_n(jobs, here, per_job_ms), "pairs": pairs}
    if name == "validate":
        rec["identical"] = all(p["identical"] for p in pairs)
        rec["excluded"] = {"keys": list(TIMING_KEYS), "topics_status_only": list(TIMING_TOPICS),
                           "text_durations": TIMING_TEXT.pattern}
    return rec


def measure(args, cmds: dict) -> dict:
    """Rounds of alternating pairs while the next pair fits in the budget (one round at least)."""
    t0 = time.perf_counter()
    pairs: dict[str, list[dict]] = {name: [] for name in cmds}
    last: dict[str, float] = {}
    for k in range(args.max_rounds):
        order = ["serial", "workers"] if k % 2 == 0 else ["workers", "serial"]
        ran = False
        for name, modes in cmds.items():
            if k and time.perf_counter() - t0 + last[name] > args.budget:
                continue
            ts = time.perf_counter()
            pairs[name].append(one_pair(name, modes, order, args.work))
            last[name] = time.perf_counter() - ts
            ran = True
            print(f"round {k}: {name} {pairs[name][-1]['wall_s']}", flush=True)
        if not ran:
            break
    return pairs


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--budget", type=float, default=360.0,
                    help="seconds for the alternating rounds (default 360; one round at least)")
    ap.add_argument("--max-rounds", type=int, default=20)
    ap.add_argument("--jobs", type=int, default=300, help="empty jobs per overhead batch")
    ap.add_argument("--overhead-repeats", type=int, default=5)
    ap.add_argument("--work", type=Path, default=Path("out/cluster-bench"))
    ap.add_argument("--out", type=Path, default=Path("docs/bench/cluster.json"))
    args = ap.parse_args()
    args.work = args.work.resolve()
    args.work.mkdir(parents=True, exist_ok=True)
    load_before, t0 = [round(x, 2) for x in os.getloadavg()], time.perf_counter()
    over = overhead(args.workers, args.jobs, args.overhead_repeats)
    cmds = commands(args.work, args.workers)
    pairs = measure(args, cmds)
    o = over["local_per_job_ms"]["median"]
    from phonglab.bench.run import machine_info  # after the clusters: imports Mitsuba here
    result = {"workers": args.workers, "budget_s": args.budget,
              "seconds": round(time.perf_counter() - t0, 1), "machine": machine_info(),
              "load_before": load_before, "load_after": [round(x, 2) for x in os.getloadavg()],
              "n_values": list(N_VALUES), "overhead": over,
              "formula": "T_N = here + sum over batches of [max(M, S/N) + o*C/N]",
              "commands": {name: {mode: shown(argv) for mode, (argv, _) in modes.items()}
                           for name, modes in cmds.items()},
              **{name: summarize(name, p, o) for name, p in pairs.items()}}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_json(args.out, result, indent=2, end="\n")
    print(f"wrote {args.out}")


def shown(argv: list[str]) -> str:
    """A command line as a user types it (``phonglab ...``, paths relative to here)."""
    return " ".join(["phonglab"] + [os.path.relpath(a) if a.startswith("/") else a
                                    for a in argv[1:]])


if __name__ == "__main__":
    main()
