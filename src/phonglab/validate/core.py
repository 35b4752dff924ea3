"""``validate_bsdf``: every topic on one BSDF, a :class:`~phonglab.verdict.Report`.

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
from ..verdict import Report
from . import lanes
from .config import options as make_options
from .cost import cost
from .energy import energy
from .gradient import gradient
from .identities import component, eval_pdf, finite, weight_and_pdf
from .inputs import ValidateError, check_topics
from .reciprocity import reciprocity
from .sampling import chi2
from .topics import TOPICS, Row


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
    if isinstance(spec, mi.BSDF):
        if params:
            raise ValidateError("parameters cannot be set on an already loaded BSDF; pass its "
                                "type name or dict instead")
        return spec, spec.class_().name() if hasattr(spec, "class_") else type(spec).__name__, None
    if isinstance(spec, (str, Path)) and str(spec).endswith(".xml"):
        path = Path(spec)
        if not path.is_file():
            raise ValidateError(f"XML file {str(spec)!r} does not exist")
        if params:
            raise ValidateError("--set cannot change an XML file's BSDF; edit the file instead")
        try:
            return mi.load_string(path.read_text()), path.name, {"file": str(path)}
        except Exception as exc:
            raise ValidateError(f"{path.name} does not load as one <bsdf>: "
                                f"{_first_line(exc)}") from exc
    if isinstance(spec, str):
        spec = {"type": spec}
    if not isinstance(spec, dict) or "type" not in spec:
        raise ValidateError("give a BSDF plugin type name, a dict with 'type', an XML file or "
                            "an mi.BSDF")
    d = {**spec, **(params or {})}
    try:
        bsdf = mi.load_dict(d)
    except Exception as exc:
        raise ValidateError(f"cannot load BSDF {spec['type']!r} ({_first_line(exc)}); check the "
                            f"type name and --set values, or register it with --plugin FILE.py"
                            ) from exc
    if not isinstance(bsdf, mi.BSDF):
        raise ValidateError(f"{spec['type']!r} is not a BSDF plugin")
    return bsdf, spec["type"], {k: (v if isinstance(v, (int, float, str, bool)) else repr(v))
                                for k, v in d.items()}


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
                  known=None, plugins=(), family=1, chi2_samples=None) -> Report:
    """Validate one BSDF on every topic (or ``topics``); see :mod:`phonglab.validate`.

    ``family``: how many BSDFs the caller judges as one family (``phonglab check``'s sanity
    cases); each statistical test is then at the Šidák level of family × m tests, so the whole
    family fails by chance with probability ALPHA (``meta["statistical_tests"]`` is that
    product).  ``chi2_samples`` replaces the χ² sample count of the (quick or default) sizes.
    """
    bsdf, label, desc, topics = prepare(spec, variant=variant, params=params, topics=topics,
                                        plugins=plugins)
    opts = make_options(quick, seed, topics)
    if chi2_samples is not None:
        opts.chi2_samples = int(chi2_samples)
    m = statistical_tests(bsdf, opts, topics) * family
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
    if family != 1:
        meta["family"] = family
    if chi2_samples is not None:
        meta["chi2_samples"] = opts.chi2_samples
    return Report(meta, rows)
