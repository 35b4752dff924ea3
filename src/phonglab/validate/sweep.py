r"""A plugin checked across its parameters, not at one point: the sweep of ``phonglab validate``.

Points.  From the parameters a kind reports for the loaded plugin (for BSDFs
:func:`phonglab.validate.bsdf.ranges.parameters`: name, loaded value, range, edges) the sweep
derives (:func:`points`):

* the given point (the plugin as loaded: its defaults and whatever the caller set);
* one parameter at a time at each value of its range (the ends, the middle and the edges
  where formulas break: 0, 1e-4, a huge exponent, equal IORs), the others as given;
* two corners: every parameter at its minimum, every one at its maximum.

Values equal to the given one are not repeated (a value the plugin neither exposes nor was
given is unknown, and every range value is tried).  ``--quick`` keeps the ends only.  A parameter
the caller pins (``--set NAME=VALUE``, or a key of the dict the plugin is loaded from) keeps
its value at every point.  A point the plugin refuses at load time (phong's k_d + k_s > 1 at
"all at maximum") is outside its range: it is reported as such, not run and not a failure.

Statistics.  With P points run, each statistical test runs at the Šidák level of P · m tests
(``family`` = P in :func:`phonglab.validate.core.run`), so the plugin as a whole still fails
by chance with probability α = :data:`phonglab.stats.ALPHA`.

Identities everywhere, physical bounds in the domain.  The consistency topics (finite,
weight, pdf, chi2, normalization, reciprocity, component, gradient, the polarized ones) are
judged at every point the plugin accepts, and so are the identities of a bound topic (an
emitter's Φ = mean sample_ray weight, the inverse-square and irradiance laws: a point light
falling off as I/r is wrong at every intensity).  A physical bound (a row of a
``Kind.bounds`` topic whose relation is "<=": a BSDF's albedo ≤ 1, :func:`is_bound`) is
judged only inside the declared (``PARAMETER_RANGES``), documented (Mitsuba's ``BUILTIN``
tables) or name-inferred (``NAMED``) domain: at the given
point and at points that vary only parameters with such a range.  A point that sets a probed
parameter (a plain float the plugin accepts up to 10⁴) is outside it: a bound that fails there
becomes an ``advice`` row (not a fail) saying which value is accepted and what it measures
("accepts kd = 10000, where directional albedo is 9499"), and the meta's ``sweep.advice``
lists, per parameter, where the excess starts (:func:`advise`).

Informational topics (``cost``: a timing that never fails) run at the given point only, and so
do the topics no swept parameter changes (``Kind.given_point_only``: a medium's phase function).

Rows.  Every row carries its point (``Row.point``: the parameters that differ from the given
point, ``{}`` there); the report's meta records the parameters swept, their ranges and where
they came from, and each point's status and time.  A plugin given as an XML file or a loaded
object cannot be reloaded with other values: it is checked at its one point, and the meta
says so.  Points are independent jobs: with a :class:`phonglab.parallel.Runner` they run on
its workers (:func:`run_point`, picklable), one job per point, as the conformance table's
cases do.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

from ..parallel import CoreMeter, Job, Runner, auto_workers
from ..verdict import Report, Row, point_label
from . import core, loading, registry
from . import profile as profile_
from .inputs import ValidateError, check_topics
from .kind import Kind


@dataclass(frozen=True)
class Point:
    """One parameter point: its parameters beyond the given ones (``{}``: the given point)."""

    params: dict

    @property
    def label(self) -> str:
        return point_label(self.params)


def points(parameters, quick: bool = False) -> list[Point]:
    """The points of a sweep over ``parameters`` (module docstring), the given point first."""
    out = [Point({})]
    for p in parameters:
        for v in p.range.values(quick):
            if p.value is None or v != p.value:
                out.append(Point({p.name: v}))
    if len(parameters) >= 2:
        ends = {p.name: p.range.values(quick=True) for p in parameters}
        out.append(Point({name: v[0] for name, v in ends.items()}))
        out.append(Point({name: v[-1] for name, v in ends.items()}))
    seen, unique = set(), []
    for pt in out:
        key = tuple(sorted(pt.params.items()))
        if key not in seen:
            seen.add(key)
            unique.append(pt)
    return unique


def sweepable(spec) -> bool:
    """Whether ``spec`` can be reloaded with other values (a type name or a dict)."""
    return isinstance(spec, dict) or (isinstance(spec, str) and not spec.endswith(".xml"))


def run(kind: Kind, base, spec, *, params=None, topics=None, seed=0, quick=False, known=None,
        plugins=(), family=1, sizes=None, runner=None, progress=None, t0=None) -> Report:
    """The sweep of a plugin already prepared at its given point (``base``, a
    :class:`~phonglab.settings.Loaded` of ``spec`` with ``params``, the variant set and the
    ``plugins`` files run: they run again only in other processes).  Each point is loaded once:
    the load that tells whether the plugin refuses it is the one its topics run on."""
    topics = check_topics(topics, kind.topics)
    t0 = time.perf_counter() if t0 is None else t0
    parameters = kind.part("parameters")
    if not sweepable(spec) or parameters is None:
        report = core.run(kind, base, topics=topics, seed=seed, quick=quick, known=known,
                          family=family, sizes=sizes)
        note = ("an XML file or a loaded object is checked at its one point: give a type name "
                "or a dict to sweep it" if parameters is not None else
                f"{kind.article} {kind.word} is checked at its given parameter point (the "
                f"{kind.word} kind has no parameter sweep)")
        report.meta["sweep"] = {"points": 1, "note": note}
        return report
    pinned = set(params or {}) | (set(spec) - {"type"} if isinstance(spec, dict) else set())
    swept = parameters(base.plugin, spec, pinned)
    pts = points(swept, quick)
    runnable, refused, loaded = [], [], []
    for pt in pts:
        try:
            target = base if not pt.params else loading.load(kind, spec,
                                                          {**(params or {}), **pt.params})
        except ValidateError as exc:
            reason = str(exc).split("; check the type name")[0].split("; the plugin files")[0]
            refused.append({"point": pt.params, "status": "refused", "reason": reason})
            continue
        runnable.append(pt)
        loaded.append(target)
    size = family * len(runnable)
    options = {"variant": base_variant(), "topics": list(topics), "seed": seed, "quick": quick,
               "known": known, "plugins": [str(p) for p in plugins], "family": size,
               "sizes": sizes, "kind": kind.name}
    with core.session(kind):             # one for every point run here
        reports, where = _run_points(spec, params or {}, runnable, loaded, options, runner,
                                     progress,
                              [t for t in topics if t not in kind.informational
                               and t not in kind.given_point_only])
    rows: list[Row] = []
    records = []
    summed: dict = {}                   # topic -> its profile summed over the points
    for pt, rep in zip(runnable, reports):
        for r in rep.rows:
            r.point = dict(pt.params)
        rows += rep.rows
        records.append({"point": pt.params, "status": "run",
                        "failing": sorted({r.topic for r in rep.failing}),
                        "seconds": rep.meta.get("seconds"),
                        "profile": profile_.total(rep.meta.get("profile") or {})})
        for topic, record in (rep.meta.get("profile") or {}).items():
            summed[topic] = profile_.add(summed.get(topic), record)
    advice = advise(rows, swept, kind.bounds)
    meta = dict(reports[0].meta)
    # every point ran at the family level: its statistical_tests is already P·m (P points)
    meta.update(seconds=round(time.perf_counter() - t0, 3),
        sweep={"points": len(runnable), "refused": len(refused),
               "parameters": [{"name": p.name, "given": p.value, "lo": p.range.lo,
                               "hi": p.range.top, "edges": list(p.range.edges),
                               "source": p.source} for p in swept],
               "pinned": sorted(pinned), "runs": records + refused, "advice": advice,
               "where": where})
    if not swept:
        meta["sweep"]["note"] = (
            f"no parameter swept: this {kind.word} declares no PARAMETER_RANGES, and no range "
            f"of it is documented or found by probing; declare PARAMETER_RANGES = "
            f"{{'name': (lo, hi)}} on its class to sweep it")
    meta.pop("topic_seconds", None)
    meta["profile"] = summed
    meta["not_covered"] = core.not_covered(kind, topics, rows)
    return Report(meta, rows)


SOURCES = {"declared": "declared by the plugin class's PARAMETER_RANGES",
           "mitsuba": "that phonglab validates it over (from Mitsuba 3.9.1's plugin reference: "
                      "phonglab.validate.{kind}.ranges.BUILTIN)",
           "named": "that Mitsuba's plugin reference gives a parameter of that name "
                    "(phonglab.validate.{kind}.ranges.NAMED; declare PARAMETER_RANGES on the "
                    "plugin class for another)"}


def check_set(kind: Kind, target, spec, params) -> None:
    """Raise :class:`ValidateError` (one sentence, before any work) when a value of
    ``params`` (``--set``) lies outside its parameter's declared or documented range."""
    domain = kind.part("domain")
    if domain is None or not params:
        return
    table, source = domain(target.plugin, spec)
    for name, value in params.items():
        rng = table.get(name)
        values = value if isinstance(value, (list, tuple)) else [value]
        if rng is None or not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                  for v in values):
            continue
        # a value within float round-off of an end (1 − 0.9999 for 1e-4) is at that end
        slack = 1e-9 * max([1.0] + [abs(e) for e in (rng.lo, rng.hi) if math.isfinite(e)])
        bad = [v for v in values if not rng.lo - slack <= v <= rng.hi + slack]
        if bad:
            raise ValidateError(
                f"{name}={bad[0]:g} is outside the range [{rng.lo:g}, {rng.hi:g}] of "
                f"{spec if isinstance(spec, str) else spec['type']}'s {name} "
                f"{SOURCES[source].format(kind=kind.name)}; give a value in it")


def outside(point: dict, swept) -> list[str]:
    """The parameters of ``point`` whose range was only probed (no declared or documented
    domain): the point is outside the domain when there is any."""
    probed = {p.name for p in swept if p.source == "probed"}
    return [name for name in point if name in probed]


def is_bound(row: Row, bounds) -> bool:
    """Whether ``row`` holds a physical bound (an albedo ≤ 1: its details' relation is "<=")
    of a bound topic, which depends on the domain, rather than an identity (Φ = mean weight,
    the inverse-square law), which holds at every value the plugin accepts."""
    return row.topic in bounds and (row.details or {}).get("relation") == "<="


def advise(rows: list[Row], swept, bounds) -> list[dict]:
    """Turn each failing bound row (:func:`is_bound`) at a point outside the
    domain (:func:`outside`) into an ``advice`` row, in place; the advice per parameter and
    topic: the accepted value nearest the given one where the bound is exceeded (where it
    starts), the farthest, and what the row measured at each."""
    given = {p.name: p.value for p in swept}
    found: dict[tuple, list] = {}
    for r in rows:
        names = outside(r.point or {}, swept) if is_bound(r, bounds) else []
        if r.status != "fail" or not names:
            continue
        values = ", ".join(f"{n} = {r.point[n]:g}" for n in names)
        r.status = "advice"
        r.reason = (f"not a fail: the plugin accepts {values} (a value probed at load time, "
                    f"outside any declared or documented range), where {_quantity(r)} is "
                    f"{_num(r.measured)} (bound {_num(r.expected)}): declare PARAMETER_RANGES "
                    f"on the plugin class or refuse the value at load time. " + r.reason)
        for n in names:
            found.setdefault((n, r.topic, r.name), []).append((r.point[n], r.measured))
    out = []
    for (name, topic, row_name), hits in found.items():
        g = given.get(name) or 0.0
        hits.sort(key=lambda h: abs(h[0] - g))
        (v0, m0), (v1, m1) = hits[0], hits[-1]
        text = (f"accepts {name} = {v0:g}, where {_quantity(row_name)} is {_num(m0)}"
                + (f" (up to {name} = {v1:g}: {_num(m1)})" if v1 != v0 else "")
                + ": declare PARAMETER_RANGES or refuse it")
        out.append({"parameter": name, "topic": topic, "starts_at": v0, "measured": m0,
                    "worst_at": v1, "worst_measured": m1, "text": text})
    return out


def _quantity(row) -> str:
    """What a bound row measures, without its bound: "directional albedo ≤ 1" -> "the
    directional albedo"."""
    name = row if isinstance(row, str) else row.name
    return "the " + name.split(" ≤")[0].split(" =")[0].split(" >")[0]


def _num(x) -> str:
    return "-" if x is None else f"{x:.4g}"


def base_variant() -> str:
    import mitsuba as mi
    return mi.variant()


def _run_points(spec, params, pts, loaded, options, runner, progress,
                other_topics) -> list[Report]:
    """(each point's report in point order, where they ran: ``workers`` and ``reason``): here
    on its ``loaded`` target, or one job per point on ``runner``; an automatic runner
    (:func:`phonglab.parallel.auto_workers`) runs the given point here and the others on the
    worker processes it starts when they would take long and cores are free.  The points
    after the given one run ``other_topics`` (no informational topic)."""
    results: dict[int, Report] = {}
    per_point = [options] + [{**options, "topics": list(other_topics)}] * (len(pts) - 1)

    def finished(i, d):
        results[i] = Report.from_dict(d) if isinstance(d, dict) else d
        if progress:
            progress(pts[i].label, results[i])

    def jobs(first: int):
        return [Job(run_point, (spec, {**params, **pts[i].params}, per_point[i]), key=str(i))
                for i in range(first, len(pts))]

    def here(first: int):
        for i in range(first, len(pts)):
            finished(i, run_loaded(loaded[i], per_point[i]))

    if runner is not None and runner.auto and len(pts) > 1:
        # the given point here, measured: its time predicts the others', and the machine's
        # other load says whether cores are free for them (phonglab.parallel: automatic)
        with CoreMeter() as meter:
            finished(0, run_loaded(loaded[0], per_point[0]))
        # each later point: the given one's time less its informational topics (cost),
        # which the others do not run
        spent = results[0].meta.get("profile") or {}
        extra = sum(r.get("seconds", 0.0) for t, r in spent.items() if t not in other_topics)
        where = auto_workers(len(pts) - 1, meter, "more points",
                             kernel_share=profile_.total(spent).get("execute_s", 0.0)
                             / max(meter.seconds, 1e-9),
                             job_seconds=max(0.0, meter.seconds - extra))
        if where["workers"] > 1:
            with Runner(workers=where["workers"], variant=runner.variant,
                        progress=runner.progress) as pool:
                pool.run(jobs(1), lambda job, d: finished(int(job.key), d), desc="sweep")
        else:
            here(1)
    elif runner is None or runner.serial:
        here(0)
        where = {"workers": 1, "reason": "serial: --workers 1 or a library call"
                 if len(pts) > 1 else "one point"}
    else:
        runner.run(jobs(0), lambda job, d: finished(int(job.key), d), desc="sweep")
        where = {"workers": runner.workers, "reason": runner.where}
    return [results[i] for i in range(len(pts))], where


def run_point(spec, params, options: dict):
    """One point of a sweep as a picklable job in another process: the variant set, the plugin
    files run, the plugin loaded with ``params``; every topic at the sweep's family level.
    Returns the report's dict."""
    kind = registry.by_name(options["kind"])
    target = loading.prepare(kind, spec, variant=options["variant"], params=params,
                          plugins=[Path(p) for p in options["plugins"]])
    return run_loaded(target, options).to_dict()


def run_loaded(target, options: dict) -> Report:
    """Every topic of ``options`` on a point's loaded ``target``, at the family level."""
    return core.run(registry.by_name(options["kind"]), target,
                    topics=tuple(options["topics"]), seed=options["seed"],
                    quick=options["quick"], known=options["known"], family=options["family"],
                    sizes=options["sizes"])
