r"""The one fresh-process timing driver: a command run as a new process, timed from outside.

Every whole-command benchmark times what a user waits for: the command starts as a fresh
child process (Python start-up, imports, the variant's set-up, JIT compilation -- Dr.Jit's
on-disk kernel cache is warm from the first run of the same kernels on -- the work, the files
written) and the parent measures around the whole process:

* wall seconds, ``time.perf_counter`` before the start and after the exit;
* the child's CPU seconds, user + system from ``os.times`` (children) before and after, so
  the CPU time of the child and of anything it waited for, and nothing of the parent.

:func:`run_child` runs one command (output discarded, captured, or written to a log file) and
checks its exit code against the codes that are results (a failing ``phonglab validate``
exits 1: a result, not a fault); :func:`run_repeated` runs it ``repeats`` times after
``warmup`` untimed runs; :func:`spread` summarizes seconds as median, [min, max] and the
values.  Alternating two configurations (A B A B ...) against drift is the caller's loop.

Users: :mod:`.fit_timing` (``phonglab fit``), ``scripts/validate_timing.py`` (``phonglab
validate``), ``scripts/planner_bench.py`` (``phonglab render``, default against planned) and
``scripts/cluster_bench.py`` (serial against a local cluster).
"""

from __future__ import annotations

import os
import statistics
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

#: ``phonglab`` as a fresh process of this interpreter.
PHONGLAB = [sys.executable, "-m", "phonglab.cli"]
#: How much of a failed child's stderr its error shows.
STDERR_TAIL = 3000


class ChildFailed(RuntimeError):
    """A timed command exited with a code that is not a result."""


@dataclass(frozen=True)
class ChildRun:
    """One fresh process: its command line, wall and CPU seconds, exit code, captured text."""

    argv: tuple[str, ...]
    seconds: float
    cpu_seconds: float
    returncode: int
    stdout: str | None = None
    stderr: str | None = None


def _cpu_children() -> float:
    t = os.times()
    return t.children_user + t.children_system


def run_child(argv: list[str], *, capture: bool = False, log: Path | None = None,
              quiet: bool = False, cwd: Path | None = None,
              accept: tuple[int, ...] | None = (0,)) -> ChildRun:
    """Run ``argv`` as a fresh process and time it from here.

    Output: discarded (stdout; stderr too when ``quiet``, else it reaches this process's
    stderr), captured as text (``capture``: :attr:`ChildRun.stdout` / ``stderr``), or both
    streams written to ``log``.  ``accept``: the exit codes that are results (None: any, the
    caller reads :attr:`ChildRun.returncode`); another one raises :class:`ChildFailed`
    naming the command, and the log file or the tail of the captured stderr.
    """
    cpu0 = _cpu_children()
    t0 = time.perf_counter()
    if log is not None:
        with open(log, "w") as fh:
            proc = subprocess.run(argv, stdout=fh, stderr=subprocess.STDOUT, cwd=cwd)
    elif capture:
        proc = subprocess.run(argv, capture_output=True, text=True, cwd=cwd)
    else:
        proc = subprocess.run(argv, stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL if quiet else None, cwd=cwd)
    seconds = time.perf_counter() - t0
    run = ChildRun(tuple(argv), seconds, _cpu_children() - cpu0, proc.returncode,
                   proc.stdout if capture else None, proc.stderr if capture else None)
    if accept is not None and run.returncode not in accept:
        where = (f"; see {log}" if log is not None
                 else f":\n{run.stderr[-STDERR_TAIL:]}" if capture else "")
        raise ChildFailed(f"{' '.join(argv)} exited {run.returncode}{where}")
    return run


def run_repeated(argv: list[str], repeats: int, warmup: int = 0, **options) -> list[ChildRun]:
    """``repeats`` timed runs of ``argv`` after ``warmup`` untimed ones (options: :func:`run_child`)."""
    for _ in range(warmup):
        run_child(argv, **options)
    return [run_child(argv, **options) for _ in range(repeats)]


def spread(values: list[float], digits: int | None = 3) -> dict:
    """Median, [min, max] and the values themselves, rounded to ``digits`` (None: not rounded)."""
    def r(v: float) -> float:
        return v if digits is None else round(v, digits)
    return {"median": r(statistics.median(values)), "spread": [r(min(values)), r(max(values))],
            "values": [r(v) for v in values]}
