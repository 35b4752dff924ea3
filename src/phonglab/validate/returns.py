r"""The returns of a Python plugin's methods, checked on one lane the way Mitsuba casts them.

Mitsuba's trampolines cast what a Python method returns to the C++ type
(:mod:`phonglab.dispatch`): a Python number, a ``mi.Float``, a ``mi.Vector3f`` or a 3-tuple
becomes a ``Spectrum``, a tuple a pair.  So each method the plugin's class defines is called
once on one lane *through the trampoline*; what it accepts is accepted -- the tutorial's delta
BSDF returning ``0.0`` from ``eval`` and ``(0.0, 0.0)`` from ``eval_pdf``, an integrator
returning its radiance as a ``mi.Vector3f`` -- and what it refuses (nanobind's
``std::bad_cast``) is one sentence (:class:`~phonglab.validate.kind.ValidateError`, exit 2)
naming the method, what it returned (the Python method called directly, to say so) and what
Mitsuba expects.

One return is misread rather than refused: an integrator whose ``sample()`` returns a bare
``mi.Spectrum`` instead of ``(L, valid, aovs)`` has its three channels unpacked as the tuple,
and the process aborts inside Dr.Jit ("Referenced an unknown variable", exit 134) with no
report.  An integrator's return is therefore first checked in Python to be a sequence of three.
Only Python-defined methods are called (a built-in's C++ methods return their own types), and
an exception inside the call is left to the topics, which report it as the plugin's error.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi

from .. import dispatch, runtime
from .kind import ValidateError

__all__ = ["check_bsdf", "check_integrator", "check_phase"]


def _defines(plugin, name: str) -> bool:
    """Whether ``plugin``'s class defines ``name`` in Python (not a Mitsuba built-in's)."""
    return any(name in cls.__dict__ for cls in type(plugin).__mro__
               if not cls.__module__.startswith(("mitsuba", "drjit", "builtins", "nanobind")))


def _what(value) -> str:
    """What a value is, in a few words: ``a tuple of 2 (Color3f, Bool)``, ``Color3f``."""
    if isinstance(value, (tuple, list)):
        inner = ", ".join(type(v).__name__ for v in value[:4]) + (", ..." if len(value) > 4 else "")
        return f"a {type(value).__name__} of {len(value)} ({inner})"
    return type(value).__name__


def _refuse(word, name, method, value, expects):
    raise ValidateError(f"{method}() of the {word} {name!r} returned {_what(value)}, which "
                        f"Mitsuba cannot take: it expects {expects}; fix the return statement "
                        f"(checked on one lane, as Mitsuba's trampoline casts it)")


def _call(method, *args):
    """(True, the return) or (False, the exception) of one call; the topics report a
    plugin's exception as its error (a ``sys.exit``/``os._exit`` too, as a failing row), so it
    is not bad input here."""
    from . import core          # the topics' time limit, if one is set (core.topic_timeout)

    try:
        with runtime.exits_intercepted(), core.within_topic_limit():
            return True, method(*args)
    except (Exception, core.TopicTimeout, SystemExit, runtime.PluginExited) as exc:
        return False, exc


def _checked(word, plugin, name, method, args, expects):
    """Call ``method`` through Mitsuba's dispatch; where the trampoline cannot cast what the
    Python method returned, say what that was (the method called directly) and refuse it."""
    ok, out = _call(getattr(dispatch.view(plugin), method), *args)
    if ok or not dispatch.is_bad_cast(out):
        return
    ok, raw = _call(getattr(plugin, method), *args)
    _refuse(word, name, method, raw if ok else out, expects)


def _sequence(out, n: int) -> bool:
    return isinstance(out, (tuple, list)) and not isinstance(out, dr.ArrayBase) and len(out) == n


def check_integrator(plugin, name: str = "integrator") -> None:
    """A Python ``SamplingIntegrator.sample()`` returns three things, ``(L, valid, aovs)``,
    that Mitsuba casts to (Spectrum, Bool, list of Float); L may be any 3-vector or number."""
    if not isinstance(plugin, mi.SamplingIntegrator) or not _defines(plugin, "sample"):
        return
    scene = mi.load_dict({"type": "scene", "shape": {"type": "sphere"},
                          "light": {"type": "constant"}})
    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(0, 1)
    ray = mi.RayDifferential3f(mi.Point3f(0, 0, -4), mi.Vector3f(0, 0, 1))
    args = (scene, sampler, ray, None, mi.Bool(True))
    expects = ("a tuple (L: the radiance, a mi.Spectrum, mi.Color3f or mi.Vector3f; valid: "
               "mi.Bool; aovs: a list of mi.Float, one per aov_names()), e.g. return L, valid, []")
    ok, out = _call(plugin.sample, *args)
    if not ok:
        return
    if not _sequence(out, 3):
        _refuse("integrator", name, "sample", out, expects)
    sampler.seed(0, 1)
    _checked("integrator", plugin, name, "sample", args, expects)


def _one_lane():
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.t = mi.Float(1.0)
    si.n = mi.Normal3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    si.wi = dr.normalize(mi.Vector3f(0.3, 0.2, 0.9))
    si.uv = mi.Point2f(0.5, 0.5)
    return mi.BSDFContext(), si, dr.normalize(mi.Vector3f(-0.2, 0.1, 0.9))


def check_bsdf(plugin, name: str = "BSDF") -> None:
    """A Python BSDF's ``sample``, ``eval``, ``pdf`` and ``eval_pdf`` (those its class defines)
    return what Mitsuba casts to (BSDFSample3f, Spectrum), Spectrum, Float, (Spectrum, Float)."""
    if not isinstance(plugin, mi.BSDF) or mi.is_polarized:
        return          # Mueller matrices: the polarized topics read them
    ctx, si, wo = _one_lane()
    active = mi.Bool(True)
    for method, args, expects in (
            ("sample", (ctx, si, mi.Float(0.5), mi.Point2f(0.3, 0.6), active),
             "a tuple (bs: mi.BSDFSample3f, weight: mi.Spectrum), e.g. return bs, weight"),
            ("eval", (ctx, si, wo, active), "one mi.Spectrum or number (the BSDF times cos θ_o)"),
            ("pdf", (ctx, si, wo, active), "one mi.Float or number"),
            ("eval_pdf", (ctx, si, wo, active),
             "a tuple (value: mi.Spectrum, pdf: mi.Float), e.g. return value, pdf")):
        if _defines(plugin, method):
            _checked("BSDF", plugin, name, method, args, expects)


def check_phase(plugin, name: str = "phase function") -> None:
    """A Python phase function's ``sample`` and ``eval_pdf`` (those its class defines) return
    what Mitsuba casts to (Vector3f wo, Spectrum weight, Float pdf) and (Spectrum, Float)."""
    if not isinstance(plugin, mi.PhaseFunction) or mi.is_polarized:
        return
    ctx = mi.PhaseFunctionContext(None)
    mei = dr.zeros(mi.MediumInteraction3f)
    mei.wi = dr.normalize(mi.Vector3f(0.3, 0.2, 0.9))
    mei.sh_frame = mi.Frame3f(mei.wi)
    mei.t = mi.Float(0.0)
    active = mi.Bool(True)
    wo = dr.normalize(mi.Vector3f(-0.2, 0.1, 0.9))
    for method, args, expects in (
            ("sample", (ctx, mei, mi.Float(0.5), mi.Point2f(0.3, 0.6), active),
             "a tuple (wo: mi.Vector3f, weight: mi.Spectrum, pdf: mi.Float), e.g. return wo, "
             "weight, pdf"),
            ("eval_pdf", (ctx, mei, wo, active),
             "a tuple (value: mi.Spectrum, pdf: mi.Float), e.g. return value, pdf")):
        if _defines(plugin, method):
            _checked("phase function", plugin, name, method, args, expects)
