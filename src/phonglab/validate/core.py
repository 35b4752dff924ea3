"""``validate_bsdf``: every topic on one BSDF, a :class:`~phonglab.validate.report.Report`.

The BSDF is given as a plugin type name, a dict for ``mi.load_dict``, an XML file holding one
``<bsdf>``, or a loaded ``mi.BSDF``.  Bad input (unknown type, unreadable file, unknown topic,
a ``--plugin`` file that fails) raises :class:`ValidateError` with one sentence, before any
check runs.
"""

from __future__ import annotations

import runpy
import time
import traceback
from pathlib import Path

import mitsuba as mi

from .. import registration
from ..settings import PluginError, load_plugin
from . import lanes
from .config import options as make_options
from .cost import cost
from .energy import energy
from .gradient import gradient
from .identities import component, eval_pdf, finite, weight_and_pdf
from .inputs import ValidateError, check_topics
from .reciprocity import reciprocity
from .report import TOPICS, Report, Row
from .sampling import chi2


def load_plugins(paths) -> None:
    """Execute each plugin file (it calls ``mi.register_bsdf`` itself) in the active variant."""
    for p in paths:
        path = Path(p)
        if not path.is_file():
            raise ValidateError(f"plugin file {str(p)!r} does not exist; give the path of a "
                                f"Python file that calls mi.register_bsdf")
        try:
            runpy.run_path(str(path), run_name="__phonglab_plugin__")
        except Exception as exc:
            raise ValidateError(f"plugin file {str(p)!r} failed: {type(exc).__name__}: "
                                f"{str(exc).splitlines()[0] if str(exc) else ''}") from exc


def _load(spec, params):
    """(bsdf, label, description for meta)."""
    try:
        return load_plugin(spec, params, kind=mi.BSDF, word="BSDF",
                           hint="check the type name and --set values, or register it with "
                                "--plugin FILE.py")
    except PluginError as exc:
        raise ValidateError(str(exc)) from exc


def _first_line(exc) -> str:
    text = str(exc).strip().splitlines()
    line = text[-1] if text else type(exc).__name__
    return line.split("] ")[-1][:300]


def statistical_tests(bsdf, opts, topics) -> int:
    """m: the number of statistical tests the run makes (χ² cells, energy cells with delta lobes)."""
    m = 0
    if "chi2" in topics and not lanes.delta_only(bsdf):
        m += len(opts.cells(opts.chi2_cos, opts.chi2_phi))
    if "energy" in topics and lanes.bsdf_has(bsdf, int(mi.BSDFFlags.Delta) |
                                             int(mi.BSDFFlags.Delta1D)):
        m += len(opts.energy_cos)
    return max(m, 1)


def prepare(spec, *, variant=None, params=None, topics=None, plugins=()):
    """Set the variant, run the plugin files, load the BSDF: everything that can be bad input."""
    topics = check_topics(topics)
    loaded = mi.variant() is not None and isinstance(spec, mi.BSDF)
    if not loaded or variant is not None:
        try:
            registration.register(variant)
        except ValueError as exc:
            raise ValidateError(str(exc)) from exc
    load_plugins(plugins)
    bsdf, label, desc = _load(spec, params)
    return bsdf, label, desc, topics


def _guarded(topic: str, runner) -> list[Row]:
    """The topic's rows; an exception (from the BSDF or the validator) is one failing row of
    that topic with the traceback in details, so the other topics still report."""
    try:
        return runner()
    except Exception as exc:
        return [Row(topic, f"{topic}: the check ran to completion", None, None, None, None,
                    "fail", f"raised {type(exc).__name__}: {_first_line(exc)}",
                    {"traceback": traceback.format_exc()[-3000:]})]


def validate_bsdf(spec, *, variant=None, params=None, topics=None, seed=0, quick=False,
                  known=None, plugins=()) -> Report:
    """Validate one BSDF on every topic (or ``topics``); see :mod:`phonglab.validate`."""
    bsdf, label, desc, topics = prepare(spec, variant=variant, params=params, topics=topics,
                                        plugins=plugins)
    opts = make_options(quick, seed, topics)
    m = statistical_tests(bsdf, opts, topics)
    runners = {
        "finite": lambda: finite(bsdf, opts),
        "eval_pdf": lambda: eval_pdf(bsdf, opts),
        "weight": lambda: weight_and_pdf(bsdf, opts, {"weight", "pdf"} & set(topics)),
        "pdf": lambda: [] if "weight" in topics else weight_and_pdf(bsdf, opts, {"pdf"}),
        "chi2": lambda: chi2(bsdf, opts, m),
        "energy": lambda: energy(bsdf, opts, m),
        "reciprocity": lambda: reciprocity(bsdf, opts),
        "component": lambda: component(bsdf, opts),
        "gradient": lambda: gradient(bsdf, opts),
        "cost": lambda: cost(bsdf, opts),
    }
    rows, seconds = [], {}
    t_all = time.perf_counter()
    for topic in topics:
        t0 = time.perf_counter()
        rows += _guarded(topic, runners[topic])
        seconds[topic] = round(time.perf_counter() - t0, 3)
    rows.sort(key=lambda r: TOPICS.index(r.topic))
    for r in rows:
        if r.status == "fail" and known and r.topic in known:
            r.status, r.reason = "KNOWN", f"{known[r.topic]} ({r.reason})"
    meta = {"bsdf": label, "spec": desc, "variant": mi.variant(), "seed": seed, "quick": quick,
            "topics": list(topics), "statistical_tests": m, "alpha": 0.01,
            "seconds": round(time.perf_counter() - t_all, 3), "topic_seconds": seconds,
            "known": dict(known or {})}
    return Report(meta, rows)
