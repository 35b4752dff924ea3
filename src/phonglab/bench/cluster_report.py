"""BENCHMARKS.md's section on a local Dask cluster against serial runs, and the expected time
on N machines (``scripts/cluster_bench.py``'s ``cluster.json``; docs/cluster.md)."""

from __future__ import annotations

from ..runtime import MIN_KERNEL_THREADS
from .report_data import RunData, fmt_g, part_record


def _med(x: dict, digits: int = 3) -> str:
    """A {median, spread} record as 'median [min, max]'."""
    lo, hi = x["spread"]
    return f"{fmt_g(x['median'], digits)} [{fmt_g(lo, digits)}, {fmt_g(hi, digits)}]"


def _cluster_n_rows(name: str, rec: dict, n_values: list[int]) -> list[str]:
    """Rows of the on-N table for one command: its batches, the part here, the total."""
    on_n, L = rec["on_n"], []
    for batch, row in on_n["batches"].items():
        j = rec["jobs"][batch]
        L.append(f"| {name}: {batch} | {j['count']} | {j['sum_s']:.3g} | {j['max_s']:.3g} | "
                 + " | ".join(f"{row[str(n)]:.3g}" for n in n_values) + " |")
    L.append(f"| {name}: here, not spread | – | – | – | "
             + " | ".join(f"{on_n['here_s']:.3g}" for _ in n_values) + " |")
    L.append(f"| **{name}: total** | | | | "
             + " | ".join(f"**{on_n['total_s'][str(n)]:.3g}**" for n in n_values) + " |")
    return L


def cluster_section(d: RunData) -> list[str]:
    """Serial against a local Dask cluster (``scripts/cluster_bench.py``'s ``cluster.json``)."""
    r = part_record(d, "cluster.json")
    if r is None:
        return []
    w, cores, ns = r["workers"], r["machine"].get("cores"), r["n_values"]
    named = {"bench": "`phonglab bench --quick --fresh`",
             "validate": "`phonglab validate --all-builtins --quick` (the conformance table)"}
    names = [n for n in ("bench", "validate") if n in r]
    L = ["\n## Serial against a local cluster, and the time on N machines\n",
         f"`scripts/cluster_bench.py` (`make bench-cluster`; [docs/cluster.md](docs/cluster.md)): "
         f"each command as a fresh process, serially and with `--workers {w}` (a Dask "
         f"LocalCluster of {w} processes) alternately, wall time of the whole command (cluster "
         f"start included), median [min, max] over the rounds that fit in {r['budget_s']:g} s, "
         f"on {cores} cores, load average {r['load_before'][0]} before and "
         f"{r['load_after'][0]} after. Speed-up = serial / {w} workers.\n",
         f"| command | rounds | serial (s) | {w} workers (s) | speed-up |", "|---|---|---|---|---|"]
    if cores and max(r["load_before"][0], r["load_after"][0]) > 0.5 * cores:
        L.insert(2, f"> **Note:** measured while other processes shared the {cores} cores (load "
                    f"average above {0.5 * cores:g}): absolute times are inflated and the speed-ups "
                    f"noisy; rerun `make bench-cluster` on a quiet machine.\n")
    for n in names:
        c = r[n]
        L.append(f"| {named[n]} | {c['rounds']} | {_med(c['serial_s'])} | {_med(c['workers_s'])} "
                 f"| {_med(c['speedup'])} |")
    if "validate" in r:
        v = r["validate"]
        L.append(f"\nThe validate JSON files of each pair are "
                 f"{'identical' if v['identical'] else '**not** identical'} apart from their "
                 f"timing fields ({', '.join(f'`{k}`' for k in v['excluded']['keys'])}; of the "
                 f"{', '.join(f'`{t}`' for t in v['excluded']['topics_status_only'])} rows, "
                 f"which are timings, only topic, name and status compared; durations in "
                 f"text, such as `mi.chi2`'s \"(25.56 ms)\" in its messages, masked).\n")
    if cores and cores <= w:
        ups = ", ".join(f"{named[n].split(' (')[0]} {fmt_g(r[n]['speedup']['median'], 3)}"
                        for n in names)
        L.append(f"On {cores} cores the {w} workers add no cores: serially Dr.Jit runs each "
                 f"kernel on {'both' if cores == 2 else f'all {cores}'} cores, and each worker "
                 f"runs Dr.Jit with max({MIN_KERNEL_THREADS}, {cores} // {w}) threads (at 1 Mitsuba hangs on EXR "
                 f"files: `tests/repro/exr_one_thread_hang.py`). What the cluster gains "
                 f"(median speed-ups: {ups}) is the time a serial run leaves a core idle or "
                 f"spinning (Python and numpy between kernels, while Dr.Jit's second thread "
                 f"waits for work), less its start and its per-job cost; its workers start "
                 f"without Dask's `MALLOC_TRIM_THRESHOLD_` (`phonglab.parallel.WORKER_ENVIRON`), "
                 f"which made them map and unmap every large buffer, and run their Dr.Jit "
                 f"kernel threads in Linux's `SCHED_IDLE` class "
                 f"(`phonglab.runtime.background_kernel_threads`), whose spin between kernels "
                 f"then takes no core from the other worker. More machines add "
                 f"cores (below).\n")
    o = r["overhead"]
    L += [f"**Per-job overhead**: {o['jobs']} empty jobs per batch, {o['repeats']} batches, "
          f"(wall time of a batch) / jobs.\n",
          "| where | per job (ms) | start (s) |", "|---|---|---|",
          f"| serial | {_med(o['serial_per_job_ms'])} | – |",
          f"| LocalCluster({w}) | {_med(o['local_per_job_ms'])} | {o['local_start_s']:.3g} |",
          f"\n**Expected time on N machines** (seconds, on paper) from the serial runs' job "
          f"times (medians over rounds), one worker per machine like this one: per batch of C "
          f"jobs whose times sum to S, the longest M, T_N ≈ max(M, S/N) + o·C/N with o = "
          f"{o['local_per_job_ms']['median']:.3g} ms, plus the command's time outside jobs "
          f"(start-up, the `jit` subprocess, charts; serial wall − ΣS), which does not spread.\n",
          "| batch | jobs C | S (s) | longest M (s) | " + " | ".join(f"N = {n}" for n in ns) + " |",
          "|---|---|---|---|" + "---|" * len(ns)]
    for n in names:
        L += _cluster_n_rows(n, r[n], ns)
    for n in names:
        lj = r[n]["on_n"]["longest_job"]
        job = f"one of its `{lj['job']}` jobs" if lj["job"] == lj["batch"] else f"`{lj['job']}`"
        L.append(f"\n{named[n]}: the longest job is {job} ({lj['seconds']:.3g} s); no N "
                 f"makes the command faster than that plus its time outside jobs.")
    return L + [""]
