r"""The kind-independent conformance runner: one plugin, every topic of its kind, one Report.

A plugin kind (:class:`~phonglab.validate.kind.Kind`, listed in
:data:`phonglab.validate.registry.KINDS`) names its Mitsuba class, its topics in table order
and the parts that run them (the sizes of a run, how many statistical tests it makes, the
table topic -> runner).  What is the same for every kind lives here:

* :func:`run`: every topic guarded (an exception, from the plugin or the validator, is one
  failing row of that topic, so the other topics still report) and timed.  The statistical rows
  share one family-wise level: each of the m tests the kind counts runs at the Šidák level
  1 − (1 − α)^(1/m) (:func:`phonglab.stats.sidak`, α = :data:`phonglab.stats.ALPHA`), so a correct
  plugin fails by chance with probability α.  A failing row becomes KNOWN (same tolerance)
  only when every one of its failing lanes lies in the *signature* of a documented cause in
  ``known`` -- the rows the cause names and the region of inputs it explains
  (:class:`~.known.Known`, :func:`~.known.mark_known`); a lane outside every signature keeps
  the row a fail, so a finding never hides a new failure of its topic.  Rows come in table
  order; the meta records the plugin, variant, seed, sizes, m, α and the timings;
* :func:`not_covered`: the applicable topics of a run that judged nothing (the report's
  ``meta["not_covered"]``; the command line does not call such a run a pass).

What a run is given -- the variant set, the ``--plugin`` files run, the plugin loaded, each bad
input one sentence before any check runs -- is :mod:`.loading`'s; the one pipeline that
conducts these steps for every caller is :mod:`.pipeline`.
"""

from __future__ import annotations

import contextlib
import time
import traceback
from dataclasses import replace

import mitsuba as mi

from .. import dispatch, runtime, stats
from . import builtin
from ..settings import Loaded
from ..verdict import NOT_APPLICABLE, Report, Row
from .inputs import ValidateError
from . import profile as profile_
from .kind import Kind, topic_page
from .known import covered_by, known_entries, mark_known
from .timeout import TopicTimeout, alarm, limit as time_limit

__all__ = ["Kind", "guarded", "not_covered", "run"]


def _first_line(exc) -> str:
    text = str(exc).strip().splitlines()
    line = text[-1] if text else type(exc).__name__
    return line.split("] ")[-1][:300]


def guarded(topic: str, runner) -> list[Row]:
    """The topic's rows; an exception (from the plugin or the validator) is one failing row of
    that topic with the traceback in details, so the other topics still report; so is a topic
    that runs past :func:`~.timeout.topic_timeout`'s limit, and a plugin that calls
    ``sys.exit`` or ``os._exit`` (:func:`phonglab.runtime.exits_intercepted`): its status never
    becomes the run's."""
    limit = time_limit()
    state = {"fired": False}
    try:
        with runtime.exits_intercepted(), alarm(limit) as state:
            return runner()
    except (TopicTimeout, SystemExit, runtime.PluginExited, Exception) as exc:
        if not (isinstance(exc, TopicTimeout) or state["fired"]):
            return _raised(topic, exc)
        return [Row(topic, f"{topic}: the check ran to completion", None, None, None, None,
                    "fail", f"did not finish within {limit:g} s (stopped by the timeout; the "
                    f"plugin's Python code may loop forever)",
                    {"traceback": traceback.format_exc()[-3000:], "timeout_s": limit})]


def _raised(topic: str, exc: Exception) -> list[Row]:
    """The failing row of a topic that raised ``exc`` (inside an ``except`` block): the
    plugin's own exception and its file:line where it came from the plugin's code
    (:func:`phonglab.dispatch.describe`, Dr.Jit's "(see above)" wrappers unwrapped); a method
    the plugin leaves unimplemented is "not implemented: <method>"."""
    cause = dispatch.root_cause(exc)
    where = dispatch.origin(cause)
    details = {"traceback": "".join(traceback.format_exception(cause))[-3000:]}
    missing = dispatch.not_implemented(cause)
    exited = dispatch.exit_call(cause)
    if exited is not None:
        details["exit"] = exited
        return [Row(topic, f"{topic}: the check ran to completion", None, None, None, None,
                    "fail", f"{exited}: a plugin must return or raise, never end the process, "
                    f"so nothing was judged", details)]
    if where is not None:
        details["plugin_error"] = {"file": where[0], "line": where[1], "function": where[2],
                                   "type": type(cause).__name__,
                                   "message": str(cause).strip()[:1000]}
        reason = f"the plugin raised {dispatch.describe(cause)}"
    else:
        reason = f"raised {type(cause).__name__}: {_first_line(cause)}"
    if missing is not None:
        details["not_implemented"] = missing
        reason = (f"{dispatch.describe(cause)}: the topic needs it (Mitsuba's rendering calls "
                  f"it), so nothing was judged")
    return [Row(topic, f"{topic}: the check ran to completion", None, None, None, None,
                "fail", reason, details)]


def not_covered(kind: Kind, topics, rows: list[Row]) -> list[str]:
    """The topics of ``topics`` that applied to the plugin and judged nothing.

    A topic *judged* something when one of its rows is ``pass``, ``fail`` or ``KNOWN``.  A topic
    that judged nothing is *not covered* -- the run says nothing of it, so it cannot be called
    a pass -- unless it genuinely does not apply, which is exactly when

    * it is informational (:attr:`Kind.informational`: ``cost`` measures and never fails), or
    * every one of its rows is skipped with ``details["not_applicable"]`` set
      (:data:`phonglab.verdict.NOT_APPLICABLE`): the skip follows from what the plugin or
      the variant *is*, never from something it failed to declare or do.  The skips marked
      so: a polarized topic in a non-polarized variant; ``gradient`` in a variant without
      automatic differentiation, of a plugin that exposes no differentiable parameter (or a
      parameter flagged non-differentiable), of a delta-only BSDF (its eval, which the topic
      differentiates, is 0), or of an integrator that is not an AD integrator; a topic with nothing to compare because
      every lobe of the BSDF is a delta (``chi2``, ``normalization``, ``weight``, ``pdf``, the
      Mueller topics) or it is black; a diffuse-reflectance contract of a BSDF with no
      Lambertian diffuse component; the radiance topics of an AOV integrator; scenes seen
      through glass for a light-tracing integrator.

    Everything else that skips a whole topic counts as not covered: an integrator whose depth
    matched no integer depth, a BSDF that sampled nothing, an emitter no reference point
    sees, a topic that produced no row at all.
    """
    out = []
    for t in topics:
        if t in kind.informational:
            continue
        mine = [r for r in rows if r.topic == t]
        if any(r.status != "skipped" for r in mine):
            continue
        if mine and all(r.details.get(NOT_APPLICABLE) for r in mine):
            continue
        out.append(t)
    return out


def parameter_values(kind: Kind, target: Loaded) -> dict:
    """The plugin's parameter values a cause's ``at`` is held against: its traversed values
    (:attr:`Kind.values`) and the numbers it was loaded with (which a plugin may not expose)."""
    values = kind.part("values")
    out = dict(values(target.plugin)) if values is not None else {}
    for name, v in (target.spec or {}).items():
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            out[name] = float(v)
    return out


def run(kind: Kind, target: Loaded, *, topics, seed=0, quick=False, known=None, family=1,
        sizes=None) -> Report:
    """Every topic of ``topics`` (checked, in table order) on the prepared ``target``.

    ``family``: how many plugins the caller judges as one family (``phonglab check``'s sanity
    cases); each statistical test is then at the Šidák level of family × m tests, so the whole
    family fails by chance with probability α (``meta["statistical_tests"]`` is that product).
    ``sizes``: fields of the kind's sizes to replace (e.g. ``{"chi2_samples": 65536}``).
    """
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        # numpy's generators refuse it inside every topic: seven failing rows, not bad input
        raise ValidateError(f"the seed must be a whole number >= 0, got {seed!r}")
    t_all = time.perf_counter()             # counting m may render (an integrator's depth)
    opts = kind.part("options")(quick, seed, topics)
    if sizes:
        opts = replace(opts, **sizes)
    if hasattr(opts, "source"):                 # topics that load the plugin again
        opts = replace(opts, source=target)
    planned = guarded("plan", lambda: kind.part("statistical_tests")(target.plugin, opts,
                                                                      topics))
    rows, seconds, profiled = [], {}, {}
    if isinstance(planned, int):
        m = planned * family
        runners = kind.part("runners")(target.plugin, opts, topics, m)
        with session(kind):
            for topic in topics:
                with profile_.Topic() as timed:
                    rows += guarded(topic, runners[topic])
                seconds[topic] = round(timed.record["seconds"], 3)
                profiled[topic] = timed.record
    else:          # counting the tests ran the plugin (an integrator's depth) and it failed
        m = 0
        (why,) = planned
        rows = [replace(why, topic=topic, name=f"{topic}: the check ran to completion",
                        reason=f"{why.reason} (while the run was planned, before any topic)")
                for topic in topics]
    rows.sort(key=lambda r: kind.topics.index(r.topic))
    values = parameter_values(kind, target)
    identity, inherited = None, []
    auto = isinstance(known, str) and known == builtin.BUILTIN
    if auto:            # the loaded built-in's findings, then its built-in children's
        identity = builtin.identify(kind, target.plugin, target.spec, target.origin)
        known = builtin.findings(kind, identity)
        values.update(identity.numbers() if identity is not None else {})
    mark_known(rows, known, values)
    if auto and any(r.status == "fail" for r in rows):
        kids = builtin.children(kind, target.plugin, kind.part("values") or (lambda p: {}))
        opts_child = {"seed": seed, "quick": quick, "family": family, "sizes": sizes}
        inherited = builtin.mark_inherited(
            rows, kids, lambda kid, topic: _child_rows(kind, kid, topic, opts_child),
            covered_by)
    meta = {kind.name: target.label, "kind": kind.name, "plugin": target.label,
            "spec": target.spec, "variant": mi.variant(), "seed": seed,
            "quick": quick, "topics": list(topics), "statistical_tests": m, "alpha": stats.ALPHA,
            "seconds": round(time.perf_counter() - t_all, 3), "topic_seconds": seconds,
            "profile": profiled,
            "not_covered": not_covered(kind, topics, rows),
            "known": {t: [k.describe() for k in known_entries(v)]
                      for t, v in (known or {}).items()}}
    if identity is not None:
        meta["builtin"] = identity.to_dict()
    if inherited:
        meta["inherited"] = inherited
    if family != 1:
        meta["family"] = family
    if sizes:
        meta["sizes"] = dict(sizes)
    for r in rows:
        r.doc = topic_page(kind.name, r.topic)
    return Report(meta, rows)


#: The rows of built-in children judged alone (:func:`_child_rows`), per process.
_CHILD_RUNS: dict = {}


def _child_rows(kind: Kind, kid, topic: str, opts: dict) -> list[Row]:
    """The rows of a plugin's built-in child judged alone on ``topic`` with its own findings
    (``known=BUILTIN``), at the plugin's seed, sizes and family; each once per process."""
    key = (kind.name, mi.variant(), kid.identity.type, str(kid.plugin), topic, repr(opts))
    if key not in _CHILD_RUNS:
        if len(_CHILD_RUNS) >= 64:
            _CHILD_RUNS.clear()
        target = Loaded(kid.plugin, kid.identity.type, None)
        _CHILD_RUNS[key] = run(kind, target, topics=(topic,), known=builtin.BUILTIN,
                               **opts).rows
    return _CHILD_RUNS[key]


def session(kind: Kind):
    """The kind's ``session`` part entered (what its topics keep across the points of one
    run; nested sessions share the outermost's), or a block that does nothing."""
    part = kind.part("session")
    return part() if part is not None else contextlib.nullcontext()
