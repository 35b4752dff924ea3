"""A bench sweep as jobs: rows written the moment a job returns them, files in a fixed order.

A sweep builds a list of :class:`phonglab.parallel.Job` (only for the rows its CSV logs do
not hold yet, so a re-run resumes) whose functions return ``[(log name, row), ...]``, and
the order of every row of the sweep (the order a serial run writes them).
:func:`run_jobs` runs the jobs on a :class:`phonglab.parallel.Runner`, appends each row to
its log as soon as its job is back (:class:`phonglab.bench.csvlog.CsvLog` fsyncs it), then
rewrites each log with the sweep's rows in that fixed order: the files of a distributed run
are the files of a serial one, whichever worker finished first.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ..parallel import Job, Runner
from .csvlog import CsvLog, fmt_value, open_log

#: A job's result: rows, each with the name of the log (phonglab.bench.config.LOGS) it goes to.
Rows = list[tuple[str, dict[str, Any]]]


def run_jobs(runner: Runner, out: Path, jobs: list[Job], order: dict[str, list[dict]],
             desc: str) -> None:
    """Run ``jobs``, writing their rows as they come, then put each log of ``order`` in order.

    ``order`` maps a log name to the key columns of every row of this sweep, in the order a
    serial run writes them.
    """
    logs = {name: open_log(out, name) for name in order}

    def write(job: Job, rows: Rows) -> None:
        for name, row in rows:
            logs[name].add(row)

    runner.run(jobs, write, desc)
    for name, keys in order.items():
        put_in_order(logs[name], keys)


def put_in_order(log: CsvLog, keys: list[dict]) -> None:
    """Rewrite ``log`` with the rows of ``keys`` in that order, in the places they hold.

    Rows of other sweeps keep their places; the rows of this sweep fill the places rows of
    this sweep hold (new rows were appended at the end), sorted by their rank in ``keys``.
    """
    rank = {tuple(fmt_value(k[c]) for c in log.key): i for i, k in enumerate(keys)}
    places = [i for i, r in enumerate(log.rows) if log.key_of(r) in rank]
    mine = sorted((log.rows[i] for i in places), key=lambda r: rank[log.key_of(r)])
    if any(log.rows[i] is not r for i, r in zip(places, mine)):
        for i, r in zip(places, mine):
            log.rows[i] = r
        log.rewrite()
