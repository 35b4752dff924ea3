"""``phonglab bench``'s entry point: run the chosen sweeps, draw the charts, record the run.

:func:`run_bench` runs the parts of :data:`PARTS` in order into one folder (each part's
rows resume from its CSV files), draws the charts, writes ``run.json`` (the sizes, the
time of each part, :func:`machine_info`, the load average before and after) and, when
asked, BENCHMARKS.md (:func:`phonglab.bench.report.write_markdown`).  A partial re-run
(a resume, or ``--only``) adds to the record of the run it continues.

The sweeps' jobs run on a :class:`phonglab.parallel.Runner` (``--workers``/``--scheduler``):
serially by default, else on Dask, with the same rows.  ``run.json`` records where they ran
and, per part, how many jobs there were and their time inside the worker (sum, median,
max: what docs/cluster.md's time on N machines is computed from).
"""

from __future__ import annotations

import json
import os
import platform
import statistics
import time
from pathlib import Path
from typing import Any, Callable, Iterable

import drjit as dr
import mitsuba as mi

from .. import __version__, registration
from ..errors import PhonglabError
from ..parallel import Runner
from .adaptive_sweeps import sweep_adaptive
from .charts import chart_error_time, chart_mis, chart_stability
from .cold_compile import sweep_cold_compile
from .config import DEFAULT_OUT, LOGS, PARTS, VARIANT, Config
from .estimator_sweeps import sweep_estimators, sweep_stability
from .render_sweeps import sweep_ratios, sweep_renders, sweep_variants, sweep_whitted_units
from .report import write_markdown
from ..engine.outputs import write_json


def machine_info() -> dict[str, Any]:
    """CPU model (from /proc/cpuinfo), cores, load, versions, GPU presence."""
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.lower().startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    try:
        load = os.getloadavg()
    except OSError:
        load = (float("nan"),) * 3
    return {
        "cpu": cpu, "cores": os.cpu_count(),
        "load_average_1_5_15": [round(x, 2) for x in load],
        "python": platform.python_version(), "platform": platform.platform(),
        "mitsuba": mi.__version__, "drjit": dr.__version__, "phonglab": __version__,
        "llvm": ".".join(map(str, dr.detail.llvm_version())) if dr.has_backend(dr.JitBackend.LLVM) else None,
        "cuda_device": bool(dr.has_backend(dr.JitBackend.CUDA)),
        "date_utc": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
    }


def process_age() -> float | None:
    """Seconds since this process started (interpreter start-up and imports included), Linux."""
    try:
        start_ticks = int(Path("/proc/self/stat").read_text().rsplit(")", 1)[1].split()[19])
        uptime = float(Path("/proc/uptime").read_text().split()[0])
        return round(uptime - start_ticks / os.sysconf("SC_CLK_TCK"), 2)
    except (OSError, ValueError, IndexError):
        return None


def _run_parts(out: Path, cfg: Config, parts: list[str], cache: Path | None, runner: Runner,
               log: Callable[[str], None]) -> tuple[dict[str, float], list[str], dict[str, Any]]:
    """Run the chosen parts in :data:`PARTS` order: (seconds per part, notes, jobs per part)."""
    notes: list[str] = []
    timings: dict[str, float] = {}
    jobs: dict[str, Any] = {}
    steps = {"estimators": lambda: sweep_estimators(out, cfg, runner),
             "stability": lambda: sweep_stability(out, cfg, runner),
             "renders": lambda: sweep_renders(out, cfg, runner, cache),
             "variants": lambda: notes.extend(sweep_variants(out, cfg, runner, cache)),
             "ratios": lambda: (sweep_ratios(out, cfg, runner),
                                sweep_whitted_units(out, cfg, runner)),
             "jit": lambda: sweep_cold_compile(out, runner.progress),
             # timed renders side by side in this process (a ratio is only fair on one machine)
             "adaptive": lambda: sweep_adaptive(out, cfg, runner.progress)}
    for name in PARTS:
        if name in parts:
            ts = time.perf_counter()
            start = len(runner.timings)
            steps[name]()
            timings[name] = round(time.perf_counter() - ts, 2)
            jobs[name] = job_summary([t.seconds for t in runner.timings[start:]])
            log(f"bench: {name} done in {timings[name]:.1f} s")
    return timings, notes, jobs


def job_summary(seconds: list[float]) -> dict[str, Any]:
    """Count, sum, median and max of job times (seconds inside the worker)."""
    if not seconds:
        return {"count": 0}
    return {"count": len(seconds), "sum_s": round(sum(seconds), 3),
            "median_s": round(statistics.median(seconds), 4), "max_s": round(max(seconds), 3)}


def _continue_record(record: dict[str, Any], old: dict[str, Any]) -> None:
    """Fold the record of a partial re-run into the one of the run it continues."""
    record["notes"] = sorted(set(old.get("notes", [])) | set(record["notes"]))
    record["seconds"] = round(old.get("seconds", 0.0) + record["seconds"], 2)
    record["parts"] = {**old.get("parts", {}), **record["parts"]}
    record["load_before"] = old.get("load_before", record["load_before"])
    record["process_seconds"] = None
    record["mode"] = old.get("mode", record["mode"])
    old_jobs = old.get("execution", {}).get("jobs", {})
    record["execution"]["jobs"] = {**old_jobs, **record["execution"]["jobs"]}


def run_bench(out: Path = DEFAULT_OUT, quick: bool = False, fresh: bool = False,
              markdown: Path | None = None, parts: Iterable[str] = PARTS,
              cache: Path | None = None, progress: bool = True,
              quick_run: Path | None = None, log: Callable[[str], None] = print,
              runner: Runner | None = None) -> dict[str, Any]:
    """Run the sweeps into ``out`` (CSV + PNG), then optionally write ``markdown``.

    ``cache`` is the reference cache folder (default: :data:`phonglab.engine.references.CACHE_DIR`).
    ``runner`` is where the jobs run (default: serially here); it is entered (a cluster
    started or reached) before any work.  Returns the run record also written to
    ``out/run.json``.
    """
    out = Path(out)
    parts = list(parts)
    unknown = [p for p in parts if p not in PARTS]
    if unknown:
        raise PhonglabError(f"unknown bench part(s) {', '.join(unknown)}; choose from {', '.join(PARTS)}")
    runner = runner or Runner(progress=progress)
    with runner:                     # a cluster that cannot be reached fails before --fresh deletes
        out.mkdir(parents=True, exist_ok=True)
        if fresh:
            for name in [filename for filename, _, _ in LOGS.values()] + ["run.json"]:
                (out / name).unlink(missing_ok=True)
        registration.register(VARIANT)
        load_before = round(os.getloadavg()[0], 2)
        t0 = time.perf_counter()
        timings, notes, jobs = _run_parts(out, Config(quick=quick), parts, cache, runner, log)
    charts = [str(p) for p in chart_error_time(out, out)]
    stability_png = chart_stability(out, out)
    if stability_png:
        charts.append(str(stability_png))
    mis_png = chart_mis(out, out)
    if mis_png:
        charts.append(str(mis_png))
    record = {"mode": "quick" if quick else "full", "seconds": round(time.perf_counter() - t0, 2),
              "process_seconds": process_age(), "parts": timings,
              "machine": machine_info(), "load_before": load_before,
              "load_after": round(os.getloadavg()[0], 2), "notes": notes, "charts": charts,
              "execution": {"where": runner.where, "jobs": jobs},
              "command": "phonglab bench" + (" --quick" if quick else "") + f" --out {out}"}
    if quick_run and Path(quick_run).is_file():   # kept: the report re-renders without it
        q = json.loads(Path(quick_run).read_text())
        record["quick_run"] = {k: q.get(k) for k in ("seconds", "process_seconds", "machine",
                                                     "load_before", "command")}
    previous = out / "run.json"
    if previous.is_file() and not fresh and set(parts) != set(PARTS):
        _continue_record(record, json.loads(previous.read_text()))
    write_json(previous, record, indent=2, end="\n")
    if markdown:
        write_markdown(out, Path(markdown), quick_run)
        log(f"bench: wrote {markdown}")
    return record
