r"""The kind-independent conformance runner: one plugin, every topic of its kind, one Report.

A plugin kind (:class:`~phonglab.validate.kind.Kind`, listed in
:data:`phonglab.validate.registry.KINDS`) names its Mitsuba class, its topics in table order
and the parts that run them (the sizes of a run, how many statistical tests it makes, the
table topic -> runner).  What is the same for every kind lives here:

* :func:`load_plugins`: run the ``--plugin`` files once, recording what each registers; a file
  that registers a name Mitsuba or phonglab already has is refused (the report would be of
  the plugin that name already meant, not of the file's), and so is one that exits
  (``sys.exit``, ``os._exit``), switches the variant or runs past :func:`topic_timeout`'s
  limit: each is one sentence, never the process's end, a hang or a report of nothing;
* :func:`load`: the plugin from a type name, a dict for ``mi.load_dict``, an XML file or a
  loaded object (:func:`phonglab.settings.load_plugin`, or the kind's own ``load`` part);
  :func:`prepare` sets the variant and does both: everything that can be bad input, each a
  one-sentence :class:`~phonglab.validate.inputs.ValidateError`, before any check runs;
* :func:`run`: every topic guarded (an exception, from the plugin or the validator, is one
  failing row of that topic, so the other topics still report) and timed.  The statistical rows
  share one family-wise level: each of the m tests the kind counts runs at the Šidák level
  1 − (1 − α)^(1/m) (:func:`phonglab.stats.sidak`, α = :data:`phonglab.stats.ALPHA`), so a correct
  plugin fails by chance with probability α.  A failing row becomes KNOWN (same tolerance)
  only when every one of its failing lanes lies in the *signature* of a documented cause in
  ``known`` -- the rows the cause names and the region of inputs it explains (:class:`Known`,
  :func:`mark_known`); a lane outside every signature keeps the row a fail, so a finding
  never hides a new failure of its topic.  Rows come in table order; the meta
  records the plugin, variant, seed, sizes, m, α and the timings;
* :func:`not_covered`: the applicable topics of a run that judged nothing (the report's
  ``meta["not_covered"]``; the command line does not call such a run a pass);
* the one pipeline that conducts these steps for every caller: :mod:`.pipeline`.
"""

from __future__ import annotations

import contextlib
import runpy
import signal
import threading
import time
import traceback
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import mitsuba as mi
import numpy as np

from .. import dispatch, registration, runtime, stats
from . import builtin
from ..settings import Loaded, PluginError, load_plugin
from ..verdict import NOT_APPLICABLE, Report, Row
from .inputs import ValidateError, check_plugin_file
from . import profile as profile_
from .kind import Kind, topic_page

__all__ = ["Kind", "Known", "guarded", "load", "load_plugins", "mark_known", "not_covered",
           "prepare", "run", "topic_timeout"]


#: Mitsuba's registration calls a plugin file may make, and the kind each registers.
REGISTER_CALLS = {"register_bsdf": "BSDF", "register_emitter": "emitter",
                  "register_integrator": "integrator", "register_texture": "texture",
                  "register_sensor": "sensor", "register_medium": "medium",
                  "register_phase": "phase function", "register_film": "film",
                  "register_shape": "shape",
                  "register_sampler": "sampler", "register_rfilter": "reconstruction filter"}


def load_plugins(paths, kind: Kind | None = None) -> list[tuple[str, str]]:
    """Execute each plugin file in the active variant; the (kind word, name) pairs they
    registered.

    A file that exits (``sys.exit``, even with status 0) or registers a name Mitsuba or
    phonglab already has is bad input (:class:`ValidateError`); with ``kind`` given, so is a
    file that registers no plugin of ``kind`` (:func:`check_registered`): the report must never
    say "all pass" of a plugin that was never loaded, or of another plugin of the same name.
    """
    by_file: dict[str, list[tuple[str, str]]] = {}
    for p in paths:
        path = check_plugin_file(p, kind.register) if kind else check_plugin_file(p)
        by_file[str(p)] = _run_plugin_file(path, kind)
    if kind is not None:
        check_registered(by_file, kind)
    return Registered(pair for pairs in by_file.values() for pair in pairs).of(by_file)


class Registered(list):
    """The (kind word, name) pairs plugin files registered; :attr:`by_file` per file."""

    by_file: dict

    def of(self, by_file: dict) -> "Registered":
        self.by_file = by_file
        return self


def check_registered(registered, kind: Kind) -> None:
    """Every plugin file registered a plugin of ``kind`` (``registered``: what
    :func:`load_plugins` returned, or its per-file dict), else :class:`ValidateError` naming
    what the file did register."""
    by_file = getattr(registered, "by_file", registered)
    for path, mine in by_file.items():
        if not any(word == kind.word for word, _ in mine):
            what = (", ".join(f"the {word} {name!r}" for word, name in mine) if mine
                    else "nothing")
            raise ValidateError(f"plugin file {path!r} registered {what}; validating "
                                f"{kind.article} {kind.word} needs a file that calls "
                                f"{kind.register}(name, constructor)")


def taken_by(name: str) -> str | None:
    """Who already has the plugin type ``name`` in the active variant: "Mitsuba" (a built-in),
    "phonglab" (:data:`phonglab.registration.PLUGINS`), or None."""
    if any(plugin == name for _, plugin, _ in registration.PLUGINS):
        return "phonglab"
    if mi.PluginManager.instance().plugin_type(name) != mi.ObjectType.Unknown:
        return "Mitsuba"
    return None


def _run_plugin_file(path: Path, kind: Kind | None) -> list[tuple[str, str]]:
    """Run one plugin file with Mitsuba's registration calls recorded; what it registered.
    A registration of a name Mitsuba or phonglab already has is refused before it happens."""
    calls: list[tuple[str, str]] = []
    originals = {name: getattr(mi, name) for name in REGISTER_CALLS if hasattr(mi, name)}
    register_call = kind.register if kind else "mi.register_*"

    class Collision(Exception):
        pass

    def recording(name, original):
        def register(plugin_name, *args, **kwargs):
            owner = taken_by(str(plugin_name))
            if owner is not None:
                raise Collision(f"plugin file {str(path)!r} registers {plugin_name!r}, a name "
                                f"{owner} already has, so validating {plugin_name!r} would "
                                f"check {owner}'s plugin, not the file's; give it a name of "
                                f"its own in the {name}() call (e.g. 'my_{plugin_name}')")
            calls.append((REGISTER_CALLS[name], str(plugin_name)))
            return original(plugin_name, *args, **kwargs)
        return register

    for name, original in originals.items():
        setattr(mi, name, recording(name, original))
    variant = mi.variant()
    try:
        with runtime.exits_intercepted(), _alarm(_TIMEOUT):
            runpy.run_path(str(path), run_name="__phonglab_plugin__")
    except Collision as exc:
        raise ValidateError(str(exc)) from None
    except (SystemExit, runtime.PluginExited) as exc:
        call = (f"os._exit({exc.status!r})" if isinstance(exc, runtime.PluginExited)
                else f"sys.exit({exc.code!r})")
        raise ValidateError(f"plugin file {str(path)!r} called {call} while it was loaded, so "
                            f"nothing was judged; a plugin file must only define its plugin "
                            f"and call {register_call}") from None
    except TopicTimeout:
        raise ValidateError(f"plugin file {str(path)!r} did not finish loading within "
                            f"{_TIMEOUT:g} s (stopped by the timeout: does it loop forever at "
                            f"import?); a plugin file must only define its plugin and call "
                            f"{register_call}") from None
    except Exception as exc:
        raise ValidateError(f"plugin file {str(path)!r} failed: "
                            f"{dispatch.describe(exc)}") from exc
    finally:
        for name, original in originals.items():
            setattr(mi, name, original)
        switched = mi.variant()
        if switched != variant and variant is not None:   # back to the one phonglab set
            registration.register(variant)
    if switched != variant:
        raise ValidateError(f"plugin file {str(path)!r} switched Mitsuba's variant to "
                            f"{switched!r} (mi.set_variant) while it was loaded, so what it "
                            f"registered is not in {variant!r}, where phonglab checks it; "
                            f"remove the mi.set_variant call (phonglab sets the variant: "
                            f"--variant)")
    return calls


def _first_line(exc) -> str:
    text = str(exc).strip().splitlines()
    line = text[-1] if text else type(exc).__name__
    return line.split("] ")[-1][:300]


def start(variant=None, spec=None, kind: Kind | None = None) -> None:
    """Set the variant (phonglab's plugins registered in it) unless ``spec`` is an object of
    ``kind`` already loaded in the active one and no variant is asked for."""
    loaded = (kind is not None and mi.variant() is not None
              and isinstance(spec, getattr(mi, kind.class_name)))
    if not loaded or variant is not None:
        try:
            registration.register(variant)
        except ValueError as exc:
            raise ValidateError(str(exc)) from exc


def load(kind: Kind, spec, params=None, registered=()) -> Loaded:
    """The plugin of ``kind`` from ``spec`` with ``params`` (its ``load`` part, or the plugin
    itself); ``registered``: what the ``--plugin`` files registered, for the fix a load
    failure suggests.  The variant must be set."""
    names = [name for word, name in registered if word == kind.word]
    hint = ("check the type name and --set values, or register it with --plugin FILE.py"
            if not names else f"the plugin files registered {', '.join(map(repr, names))}")
    own = kind.part("load")
    try:
        with _alarm(_TIMEOUT) as state:  # the constructor, traverse(), each method once
            try:
                if own is not None:
                    loaded = own(spec, params, hint)
                else:
                    loaded = load_plugin(spec, params, kind=getattr(mi, kind.class_name),
                                         word=kind.word, hint=hint)
            except PluginError as exc:
                if state["fired"]:       # Mitsuba's loader quoted the timeout as text
                    raise TopicTimeout() from None
                raise ValidateError(str(exc)) from exc
            _check_traverse(kind, loaded)
            returns = kind.part("returns")   # the Python methods' return types, on one lane
            if returns is not None:
                returns(loaded.plugin, loaded.label)
    except TopicTimeout:
        name = f" {spec!r}" if isinstance(spec, str) else ""
        raise ValidateError(f"loading the {kind.word}{name} (its constructor, "
                            f"traverse() and one call of each method) did not finish within "
                            f"{_TIMEOUT:g} s (stopped by the timeout: does the plugin's Python "
                            f"code loop forever?)") from None
    files = tuple(str(Path(f).resolve()) for f in getattr(registered, "by_file", {}))
    return loaded._replace(files=files) if files else loaded


def _check_traverse(kind: Kind, loaded: Loaded) -> None:
    """``mi.traverse`` of the plugin works, else one sentence naming the plugin's own error
    and its file:line (an API renamed before 3.9.1: ``callback.put_parameter`` -> ``put``)."""
    plugin = loaded.plugin
    if not isinstance(plugin, mi.Object):       # a kind's holder (an emitter's Setup ...)
        plugin = next((v for v in vars(plugin).values() if isinstance(v, mi.Object)), None)
    if plugin is None:
        return
    try:
        mi.traverse(plugin)
    except Exception as exc:
        raise ValidateError(f"traverse() of the {kind.word} {loaded.label!r} raised "
                            f"{dispatch.describe(exc)}; Mitsuba calls traverse() to expose its "
                            f"parameters (mi.traverse, parameter updates, phonglab's sweep and "
                            f"gradient): fix it (3.9.1's callback is callback.put(name, value, "
                            f"flags)) or leave traverse() out") from exc


def prepare(kind: Kind, spec, *, variant=None, params=None, plugins=()) -> Loaded:
    """Set the variant, run the plugin files, load the plugin: everything that can be bad input."""
    start(variant, spec, kind)
    return load(kind, spec, params, load_plugins(plugins, kind))


class TopicTimeout(BaseException):
    """Raised by SIGALRM inside a topic that ran past :func:`topic_timeout`'s limit.  A
    BaseException, so a plugin's own ``except Exception`` does not swallow it."""


#: The limit of one topic in seconds (None: none), set by :func:`topic_timeout`.
_TIMEOUT: float | None = None


@contextlib.contextmanager
def topic_timeout(seconds: float | None):
    """For the block, each topic :func:`run` runs is stopped after ``seconds`` and becomes one
    failing row ("did not finish within N s"); the other topics still run.

    How: SIGALRM (``signal.setitimer``), whose Python handler raises :class:`TopicTimeout` in
    the main thread at its next bytecode -- so it stops Python code (a plugin's ``eval`` that
    loops forever), not a compiled Dr.Jit kernel or a C++ call, which run to their end before
    Python sees the signal (a kernel that never ends still hangs).  Only in the main thread and
    on POSIX; elsewhere the limit is not applied.  SIGINT is routed separately
    (:func:`phonglab.runtime.interrupts_routed`) and is not touched."""
    global _TIMEOUT
    if seconds is not None and (isinstance(seconds, bool) or not isinstance(seconds, (int, float))
                                or not seconds > 0 or seconds == float("inf")):
        raise ValidateError(f"the timeout must be a number of seconds > 0, got {seconds!r}")
    old, _TIMEOUT = _TIMEOUT, seconds
    try:
        yield
    finally:
        _TIMEOUT = old


@contextlib.contextmanager
def _alarm(seconds: float | None):
    """For the block, SIGALRM after ``seconds`` raises :class:`TopicTimeout`; yields a dict
    whose "fired" says whether it did (a C++ caller in between -- ``mi.render``'s custom op --
    may re-raise it as a RuntimeError).  Inside a block whose timer is still running (loading
    a plugin inside a ``check`` that is itself limited) the outer limit holds and no second
    timer is set."""
    state = {"fired": False}
    if (not seconds or not hasattr(signal, "setitimer")
            or threading.current_thread() is not threading.main_thread()
            or signal.getitimer(signal.ITIMER_REAL)[0] > 0):   # an outer limit holds already
        yield state
        return

    def expired(signum, frame):
        state["fired"] = True
        raise TopicTimeout()

    previous = signal.signal(signal.SIGALRM, expired)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield state
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def within_topic_limit():
    """:func:`_alarm` at the limit :func:`topic_timeout` set (none: no limit), for a call that
    runs a plugin's Python code outside a topic (the return-type check of :mod:`.returns`)."""
    return _alarm(_TIMEOUT)


def guarded(topic: str, runner) -> list[Row]:
    """The topic's rows; an exception (from the plugin or the validator) is one failing row of
    that topic with the traceback in details, so the other topics still report; so is a topic
    that runs past :func:`topic_timeout`'s limit, and a plugin that calls ``sys.exit`` or
    ``os._exit`` (:func:`phonglab.runtime.exits_intercepted`): its status never becomes the
    run's."""
    limit = _TIMEOUT
    state = {"fired": False}
    try:
        with runtime.exits_intercepted(), _alarm(limit) as state:
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
        reason = (f"{dispatch.describe(cause)}: the topic needs it (Mitsuba's integrators call "
                  f"it), so nothing was judged")
    return [Row(topic, f"{topic}: the check ran to completion", None, None, None, None,
                "fail", reason, details)]


@dataclass(frozen=True)
class Known:
    """A documented cause of failing rows, matched by its signature, never by topic alone.

    ``rows``: the names of the rows it explains (() -- every row of its topic); ``region``: the
    failing lanes it explains (an object with ``covers(row)`` -> one boolean per failing lane
    or None, and ``text``; :mod:`phonglab.validate.bsdf.signatures`), None for all of them.
    A plain string in ``known`` is a cause with neither: what a user writes by hand for a
    topic they have judged as a whole.
    """

    cause: str
    rows: tuple[str, ...] = ()
    region: Any = None
    key: str = ""                  #: the finding's id, if it is one
    #: parameter values the cause holds at ((name, value) or (name, (lo, hi)), ...): it
    #: explains nothing at a point where a named parameter has another value (outside
    #: [lo, hi]) or none (() -- at every point)
    at: tuple[tuple[str, Any], ...] = ()

    def holds_at(self, values: dict | None) -> bool:
        """Whether the plugin's parameter ``values`` (name -> float) meet :attr:`at`."""
        for name, v in self.at:
            got = (values or {}).get(name)
            if not isinstance(got, (int, float)):
                return False
            lo, hi = v if isinstance(v, tuple) else (v, v)
            slack = 1e-6 * max(1.0, abs(lo), abs(hi))
            if not lo - slack <= got <= hi + slack:
                return False
        return True

    def names(self, row: Row) -> bool:
        """Whether the cause names ``row`` (a parameter row ``nested.eta.value`` matches
        ``eta.value``: the same parameter of a nested plugin)."""
        return not self.rows or any(row.name == n or row.name.endswith("." + n)
                                    for n in self.rows)

    def describe(self) -> str:
        """One line for the report's meta: the cause, and the signature when it has one."""
        where = []
        if self.rows:
            where.append("rows " + ", ".join(repr(r) for r in self.rows))
        if self.region is not None:
            where.append(self.region.text)
        if self.at:
            where.append("at " + at_text(self.at))
        return self.cause + (f" [signature: {'; '.join(where)}]" if where else "")


def at_text(at) -> str:
    """``int_ior in [2, 3], diffuse_reflectance = 1``: the parameter values a cause holds at."""
    return ", ".join(f"{n} in [{v[0]:g}, {v[1]:g}]" if isinstance(v, tuple) else f"{n} = {v:g}"
                     for n, v in at)


def known_entries(value) -> tuple[Known, ...]:
    """A ``known`` value (a cause string, a :class:`Known`, or a sequence of them) as Knowns."""
    if value is None:
        return ()
    if isinstance(value, (str, Known)):
        value = (value,)
    return tuple(Known(v) if isinstance(v, str) else v for v in value)


def _failing_count(row: Row) -> int:
    lanes = row.failing_lanes
    return len(next(iter(lanes.values()))) if lanes else 1


def mark_known(rows: list[Row], known, values: dict | None = None) -> None:
    """A failing row whose every failing lane lies in the signature of a documented cause that
    names it (and holds at the plugin's parameter ``values``) becomes KNOWN, its reason
    prefixed by the cause(s); a failing lane outside every such signature keeps the row a
    fail, and its reason and details say how many lanes lie outside and where the first one
    is (a new failure hides behind no old finding)."""
    for r in rows:
        causes = [k for k in known_entries((known or {}).get(r.topic))
                  if k.names(r) and k.holds_at(values)]
        if r.status != "fail" or not causes:
            continue
        n = _failing_count(r)
        covered, used = _coverage(r, causes)
        if covered.all():
            r.status = "KNOWN"
            r.reason = f"{'; '.join(k.cause for k in used)} ({r.reason})"
            keys = [k.key for k in used if k.key]
            if keys:
                r.details["known_by"] = keys
            continue
        outside = int(n - covered.sum())
        texts = "; ".join(dict.fromkeys(k.region.text for k in causes if k.region is not None))
        r.reason += (f"; {outside} of {n} failing lanes lie outside every documented signature "
                     f"({texts})")
        first = int(np.flatnonzero(~covered)[0])
        r.details["outside_signature"] = {
            "lanes": outside, "of": n, "findings": [k.key or k.cause[:80] for k in causes],
            "first": {k: _lane_value(v, first) for k, v in (r.failing_lanes or {}).items()}}


def _coverage(row: Row, causes) -> tuple[np.ndarray, list]:
    """Which failing lanes of ``row`` lie in the signature of one of ``causes``, and the
    causes that cover any."""
    n = _failing_count(row)
    covered = np.zeros(n, bool)
    used = []
    for k in causes:
        mask = np.ones(n, bool) if k.region is None else k.region.covers(row)
        if mask is None or len(mask) != n or not np.any(mask):
            continue
        covered |= np.asarray(mask, bool)
        used.append(k)
    return covered, used


def covered_by(row: Row, causes) -> tuple[bool, list]:
    """(every failing lane of ``row`` lies in a signature of ``causes``, the causes used): the
    rule :func:`mark_known` applies."""
    covered, used = _coverage(row, causes)
    return bool(covered.all()), used


def _lane_value(values, i):
    v = values[i]
    if isinstance(v, dict):          # a χ² cell's record: its incidence only
        return {k: v[k] for k in ("theta_deg", "phi", "p_value") if k in v}
    return np.asarray(v).tolist()


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
