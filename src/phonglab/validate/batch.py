"""Many plugins as independent jobs: :func:`run_case` (picklable, one case -> one report dict).

``phonglab validate --all-builtins`` and ``make conformance`` map :func:`run_case` over the
cases of a kind's conformance table (:func:`phonglab.validate.registry.catalogue`; the kind is
``options["kind"]``, :data:`~phonglab.validate.registry.DEFAULT` when it names none).  Each
job sets its own variant, loads its own plugin and returns plain JSON-able data, so an execution layer (a process pool, ``dask.distributed``'s
``client.map(run_case, labels, options=...)``) can run them anywhere; Mitsuba/Dr.Jit state is
per process, so jobs parallelize over processes, not threads.  A case that cannot be loaded
becomes a report with one failing ``finite`` row naming the error, not an exception: one bad
case never loses the others' results.
"""

from __future__ import annotations

import json
import os
import time
import traceback
from pathlib import Path

from ..parallel import Job, Runner
from ..engine.outputs import jsonable
from ..verdict import Report, Row, point_label
from . import registry
from .. import validate as face
from .kind import Kind


def kind_of(options: dict | None) -> Kind:
    """The kind whose table ``options`` run: ``options["kind"]``, else
    :data:`~phonglab.validate.registry.DEFAULT`."""
    name = (options or {}).get("kind")
    return registry.by_name(name) if name else registry.DEFAULT


def find_case(case, kind: Kind):
    """A case of ``kind``'s catalogue (:func:`~phonglab.validate.registry.catalogue`)
    from itself or its label."""
    if not isinstance(case, str):
        return case
    return registry.catalogue(kind.name).find(case)


def _validate(case, kind: Kind, options: dict) -> Report:
    """The kind's validator on one case (with the case's own options, e.g. an area emitter's
    shape; a case with ``skip`` set: one skipped row saying why)."""
    common = dict(variant=case.resolved_variant(), known=case.known,
                  seed=options.get("seed", 0), quick=options.get("quick", False),
                  topics=options.get("topics"))
    if getattr(case, "skip", ""):
        return Report({kind.name: case.plugin, "variant": case.resolved_variant()},
                      [Row("finite", "the case loads and runs", None, None, None, None,
                           "skipped", case.skip)])
    return getattr(face, kind.function)(case.spec, **common, sweep=options.get("sweep", False),
                                        **getattr(case, "options", {}))


def run_case(case, options: dict | None = None) -> dict:
    """Validate one case (a case of the table or its label); ``options``: seed, quick, topics,
    ``kind`` (whose table: :func:`kind_of`) and ``sweep`` (True: across the case's parameter
    sweep, the keys of its spec pinned, so the case is the sweep's given point; default: the
    case's point alone).

    Returns ``Report.to_dict()`` with ``meta["case"]`` set to the label and what the case adds
    (its ``meta()``: its note, ...).
    """
    options = dict(options or {})
    kind = kind_of(options)
    case = find_case(case, kind)
    t0 = time.perf_counter()
    try:
        report = _validate(case, kind, options)
    except Exception as exc:      # one broken case is a result, not the end of the batch
        report = Report({kind.name: case.plugin, "variant": case.variant, "error": repr(exc)},
                        [Row("finite", "the case loads and runs", None, None, None, None, "fail",
                             f"{type(exc).__name__}: {str(exc).splitlines()[0][:300] if str(exc) else ''}",
                             {"traceback": traceback.format_exc()[-2000:]})])
    d = report.to_dict()
    d["meta"].update(case=case.label, **case.meta(),
                     wall_seconds=round(time.perf_counter() - t0, 3))
    return d


class CaseLog:
    """The finished cases of one ``--all-builtins`` run, kept as they finish so that an
    interrupted run loses none of them and a rerun with the same options resumes.

    ``<json>.partial.jsonl`` beside the final JSON: a first line with the run's options, then
    one line per finished case report, each flushed and fsync'ed as it is appended (as the
    bench's CSV rows are).  A rerun with other options starts afresh; a last line cut short
    by a crash is dropped (that case runs again); the log is removed once the final JSON is
    written.
    """

    def __init__(self, json_path: str | Path, options: dict):
        self.path = Path(str(json_path) + ".partial.jsonl")
        self.options = jsonable(dict(options))
        self.done: dict[str, dict] = {}
        lines = self.path.read_text().splitlines() if self.path.is_file() else []
        try:
            same = bool(lines) and json.loads(lines[0]) == {"options": self.options}
        except ValueError:
            same = False
        for line in lines[1:] if same else ():
            try:
                report = json.loads(line)
            except ValueError:       # cut short by the interruption: that case runs again
                break
            self.done[report["meta"]["case"]] = report
        if not same:
            self._append({"options": self.options}, mode="w")

    def add(self, report: dict) -> None:
        self.done[report["meta"]["case"]] = report
        self._append(report)

    def _append(self, data: dict, mode: str = "a") -> None:
        self.path.parent.mkdir(parents=True, exist_ok=True)
        with open(self.path, mode) as f:
            f.write(json.dumps(data, allow_nan=False) + "\n")
            f.flush()
            os.fsync(f.fileno())

    def remove(self) -> None:
        self.path.unlink(missing_ok=True)


def run_all(cases=None, options: dict | None = None, progress=None,
            runner: Runner | None = None, log: CaseLog | None = None) -> dict:
    """Every case in order: ``{"meta": {...}, "reports": [run_case(...), ...]}``.

    ``runner`` (:class:`phonglab.parallel.Runner`) is where the cases run: one job each,
    sent by label (a Case holds Mitsuba objects that do not pickle), ``progress(report)``
    called as each finishes; the reports come back in case order.  Default: serially here.
    ``log`` (:class:`CaseLog`): cases it already holds are not run again, each new one is
    added to it as it finishes.
    """
    if cases is None:
        cases = registry.catalogue(kind_of(options).name).cases()
    results = dict(log.done) if log is not None else {}
    todo = [case for case in cases if case.label not in results]

    def finished(d):
        results[d["meta"]["case"]] = d
        if log is not None:
            log.add(d)
        if progress:
            progress(d)

    if runner is None or runner.serial:
        for case in todo:
            finished(run_case(case, options))
    else:
        jobs = [Job(run_case, (case.label, options), key=case.label) for case in todo]
        runner.run(jobs, lambda job, d: finished(d), desc="validate")
    reports = [results[case.label] for case in cases]
    failed = [r["meta"]["case"] for r in reports
              if any(x["status"] == "fail" for x in r["results"])]
    return {"meta": {"cases": len(reports), "failed": failed, "options": dict(options or {})},
            "reports": reports}


def false_failures(cases, seeds: int, quick: bool = False, plugins=(), sweep=False, *,
                   kind: str) -> dict:
    """Run each case over seeds 0..seeds−1: {label: [(seed, failing topics), ...]}, one pair
    per seed (an empty list: the run passed; in a sweep a topic is named with its point,
    ``chi2 at exponent=1``).

    ``cases``: plugin names, or {label: (spec, params)} or {label: (spec, params, known)}
    (``known``: the documented causes, as for :func:`phonglab.validate.validate`), all of one
    ``kind`` (the name of the kind whose topics run); ``plugins``: files that register
    them; ``sweep``: each run across the plugin's parameter sweep (``params`` pinned).
    Its informational topics (``cost``) are left out: they never fail.  For a correct plugin every failing
    run is a false failure and each run fails with probability ≤ ALPHA by construction; for a
    planted defect every passing run (no failing topic) is a false pass.
    """
    k = registry.by_name(kind)
    topics = [t for t in k.topics if t not in k.informational]
    if not isinstance(cases, dict):
        cases = {name: (name, None) for name in cases}
    out = {}
    for label, (spec, params, *known) in cases.items():
        out[label] = []
        for seed in range(seeds):
            report = face.validate(spec, params=params or None, seed=seed, quick=quick,
                                   topics=topics, plugins=list(plugins), sweep=sweep,
                                   known=known[0] if known else None)
            out[label].append((seed, sorted({r.topic if r.point is None
                                              else f"{r.topic} at {point_label(r.point)}"
                                              for r in report.failing})))
    return out
