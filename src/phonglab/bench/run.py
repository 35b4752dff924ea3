"""``phonglab bench``'s entry point: run the chosen sweeps, draw the charts, record the run.

:func:`run_bench` runs the parts of :data:`PARTS` in order into one folder (each part's
rows resume from its CSV files), draws the charts, writes ``run.json`` (the sizes, the
time of each part, :func:`machine_info`, the load average before and after) and, when
asked, BENCHMARKS.md (:func:`phonglab.bench.report.write_markdown`).  A partial re-run
(a resume, or ``--only``) adds to the record of the run it continues.
"""

from __future__ import annotations

import json
import os
import platform
import time
from pathlib import Path
from typing import Any, Callable, Iterable

import drjit as dr
import mitsuba as mi

from .. import __version__, registration
from ..errors import PhonglabError
from .charts import chart_error_time, chart_stability
from .adaptive_sweeps import sweep_adaptive
from .cold_compile import sweep_cold_compile
from .config import DEFAULT_OUT, LOGS, PARTS, VARIANT, Config
from .estimator_sweeps import sweep_estimators, sweep_stability
from .render_sweeps import sweep_ratios, sweep_renders, sweep_variants
from .report import write_markdown


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


def _run_parts(out: Path, cfg: Config, parts: list[str], cache: Path | None, progress: bool,
               log: Callable[[str], None]) -> tuple[dict[str, float], list[str]]:
    """Run the chosen parts in :data:`PARTS` order: (seconds per part, notes)."""
    notes: list[str] = []
    timings: dict[str, float] = {}
    steps = {"estimators": lambda: sweep_estimators(out, cfg, progress),
             "stability": lambda: sweep_stability(out, cfg, progress),
             "renders": lambda: sweep_renders(out, cfg, cache, progress),
             "variants": lambda: notes.extend(sweep_variants(out, cfg, cache, progress)),
             "ratios": lambda: sweep_ratios(out, cfg, progress),
             "jit": lambda: sweep_cold_compile(out, progress),
             "adaptive": lambda: sweep_adaptive(out, cfg, progress)}
    for name in PARTS:
        if name in parts:
            ts = time.perf_counter()
            steps[name]()
            timings[name] = round(time.perf_counter() - ts, 2)
            log(f"bench: {name} done in {timings[name]:.1f} s")
    return timings, notes


def _continue_record(record: dict[str, Any], old: dict[str, Any]) -> None:
    """Fold the record of a partial re-run into the one of the run it continues."""
    record["notes"] = sorted(set(old.get("notes", [])) | set(record["notes"]))
    record["seconds"] = round(old.get("seconds", 0.0) + record["seconds"], 2)
    record["parts"] = {**old.get("parts", {}), **record["parts"]}
    record["load_before"] = old.get("load_before", record["load_before"])
    record["process_seconds"] = None
    record["mode"] = old.get("mode", record["mode"])


def run_bench(out: Path = DEFAULT_OUT, quick: bool = False, fresh: bool = False,
              markdown: Path | None = None, parts: Iterable[str] = PARTS,
              cache: Path | None = None, progress: bool = True,
              quick_run: Path | None = None, log: Callable[[str], None] = print) -> dict[str, Any]:
    """Run the sweeps into ``out`` (CSV + PNG), then optionally write ``markdown``.

    ``cache`` is the reference cache folder (default: :data:`phonglab.references.CACHE_DIR`).
    Returns the run record also written to ``out/run.json``.
    """
    out = Path(out)
    parts = list(parts)
    unknown = [p for p in parts if p not in PARTS]
    if unknown:
        raise PhonglabError(f"unknown bench part(s) {', '.join(unknown)}; choose from {', '.join(PARTS)}")
    out.mkdir(parents=True, exist_ok=True)
    if fresh:
        for name in [filename for filename, _, _ in LOGS.values()] + ["run.json"]:
            (out / name).unlink(missing_ok=True)
    registration.register(VARIANT)
    load_before = round(os.getloadavg()[0], 2)
    t0 = time.perf_counter()
    timings, notes = _run_parts(out, Config(quick=quick), parts, cache, progress, log)
    charts = [str(p) for p in chart_error_time(out, out)]
    stability_png = chart_stability(out, out)
    if stability_png:
        charts.append(str(stability_png))
    record = {"mode": "quick" if quick else "full", "seconds": round(time.perf_counter() - t0, 2),
              "process_seconds": process_age(), "parts": timings,
              "machine": machine_info(), "load_before": load_before,
              "load_after": round(os.getloadavg()[0], 2), "notes": notes, "charts": charts,
              "command": "phonglab bench" + (" --quick" if quick else "") + f" --out {out}"}
    previous = out / "run.json"
    if previous.is_file() and not fresh and set(parts) != set(PARTS):
        _continue_record(record, json.loads(previous.read_text()))
    previous.write_text(json.dumps(record, indent=2) + "\n")
    if markdown:
        write_markdown(out, Path(markdown), quick_run)
        log(f"bench: wrote {markdown}")
    return record
