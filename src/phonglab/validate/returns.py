r"""The types a Python plugin's methods return, checked in Python on a one-lane call before
Dr.Jit sees them.

Mitsuba's trampolines cast what a Python ``sample()``/``eval()`` returns to C++ types.  Some
wrong returns are not refused there but misread: an integrator whose ``sample()`` returns a
bare ``mi.Spectrum`` instead of ``(L, valid, aovs)`` has its three channels unpacked as the
tuple, and the process aborts inside Dr.Jit ("Referenced an unknown variable", exit 134) with
no report.  So each method the plugin's Python class defines is called once on one lane and
what it returned is compared with what Mitsuba expects; a mismatch is one sentence
(:class:`~phonglab.validate.kind.ValidateError`, exit 2) naming the method, what it returned
and what Mitsuba expects.  Only Python-defined methods are called (a built-in's C++ methods
return their own types), and an exception inside the call is left to the topics, which report
it as a failing row.

Accepted where Mitsuba accepts it (tried on 3.9.1): a Spectrum slot takes ``mi.Spectrum``,
``mi.Float`` or a Python number (broadcast); a tuple may be a list.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi

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


def _spectrum(v) -> bool:
    return (isinstance(v, (mi.Spectrum, mi.Float)) or type(v) in (float, int)) \
        and not isinstance(v, bool)


def _float(v) -> bool:
    return isinstance(v, mi.Float) or (type(v) in (float, int))


def _mask(v) -> bool:
    return isinstance(v, (mi.Bool, bool))


def _refuse(word, name, method, value, expects):
    raise ValidateError(f"{method}() of the {word} {name!r} returned {_what(value)}, but Mitsuba "
                        f"expects {expects}; fix the return statement (checked on one lane "
                        f"before Dr.Jit sees it: a wrong tuple can abort the process inside "
                        f"Dr.Jit)")


def _call(method, *args):
    """The method's return, None when it raised (the topics report that as a failing row)."""
    from . import core          # the topics' time limit, if one is set (core.topic_timeout)

    try:
        with core.within_topic_limit():
            return True, method(*args)
    except (Exception, core.TopicTimeout):
        return False, None


def check_integrator(plugin, name: str = "integrator") -> None:
    """A Python ``SamplingIntegrator.sample()`` returns ``(Spectrum, Bool, list of Float)``."""
    if not isinstance(plugin, mi.SamplingIntegrator) or not _defines(plugin, "sample"):
        return
    scene = mi.load_dict({"type": "scene", "shape": {"type": "sphere"},
                          "light": {"type": "constant"}})
    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(0, 1)
    ray = mi.Ray3f(mi.Point3f(0, 0, -4), mi.Vector3f(0, 0, 1))
    ok, out = _call(plugin.sample, scene, sampler, ray, None, mi.Bool(True))
    if not ok:
        return
    expects = ("a tuple (L: mi.Spectrum, valid: mi.Bool, aovs: a list of mi.Float), e.g. "
               "return L, valid, []")
    if not isinstance(out, (tuple, list)) or isinstance(out, dr.ArrayBase) or len(out) != 3:
        _refuse("integrator", name, "sample", out, expects)
    L, valid, aovs = out
    if not _spectrum(L) or not _mask(valid) or not isinstance(aovs, (list, tuple)) \
            or not all(_float(a) for a in aovs):
        _refuse("integrator", name, "sample", out, expects)


def _one_lane():
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.t = mi.Float(1.0)
    si.n = mi.Normal3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    si.wi = dr.normalize(mi.Vector3f(0.3, 0.2, 0.9))
    si.uv = mi.Point2f(0.5, 0.5)
    return mi.BSDFContext(), si, dr.normalize(mi.Vector3f(-0.2, 0.1, 0.9))


def check_bsdf(plugin, name: str = "BSDF") -> None:
    """A Python BSDF's ``sample`` returns ``(BSDFSample3f, Spectrum)``, ``eval`` a Spectrum,
    ``pdf`` a Float and ``eval_pdf`` ``(Spectrum, Float)`` -- those its class defines."""
    if not isinstance(plugin, mi.BSDF) or mi.is_polarized:
        return          # Mueller matrices: the polarized topics read them
    ctx, si, wo = _one_lane()
    active = mi.Bool(True)
    if _defines(plugin, "sample"):
        ok, out = _call(plugin.sample, ctx, si, mi.Float(0.5), mi.Point2f(0.3, 0.6), active)
        if ok and (not isinstance(out, (tuple, list)) or isinstance(out, dr.ArrayBase)
                   or len(out) != 2 or not isinstance(out[0], mi.BSDFSample3f)
                   or not _spectrum(out[1])):
            _refuse("BSDF", name, "sample", out, "a tuple (bs: mi.BSDFSample3f, weight: "
                    "mi.Spectrum), e.g. return bs, weight")
    if _defines(plugin, "eval"):
        ok, out = _call(plugin.eval, ctx, si, wo, active)
        if ok and not _spectrum(out):
            _refuse("BSDF", name, "eval", out, "one mi.Spectrum (the BSDF times cos θ_o)")
    if _defines(plugin, "pdf"):
        ok, out = _call(plugin.pdf, ctx, si, wo, active)
        if ok and not _float(out):
            _refuse("BSDF", name, "pdf", out, "one mi.Float")
    if _defines(plugin, "eval_pdf"):
        ok, out = _call(plugin.eval_pdf, ctx, si, wo, active)
        if ok and (not isinstance(out, (tuple, list)) or isinstance(out, dr.ArrayBase)
                   or len(out) != 2 or not _spectrum(out[0]) or not _float(out[1])):
            _refuse("BSDF", name, "eval_pdf", out, "a tuple (value: mi.Spectrum, pdf: "
                    "mi.Float), e.g. return value, pdf")


def _tuple(out, n: int) -> bool:
    return isinstance(out, (tuple, list)) and not isinstance(out, dr.ArrayBase) and len(out) == n


def check_phase(plugin, name: str = "phase function") -> None:
    """A Python phase function's ``sample`` returns ``(Vector3f wo, Spectrum weight, Float
    pdf)`` and ``eval_pdf`` ``(Spectrum, Float)`` -- those its class defines."""
    if not isinstance(plugin, mi.PhaseFunction) or mi.is_polarized:
        return
    ctx = mi.PhaseFunctionContext(None)
    mei = dr.zeros(mi.MediumInteraction3f)
    mei.wi = dr.normalize(mi.Vector3f(0.3, 0.2, 0.9))
    mei.sh_frame = mi.Frame3f(mei.wi)
    mei.t = mi.Float(0.0)
    active = mi.Bool(True)
    if _defines(plugin, "sample"):
        ok, out = _call(plugin.sample, ctx, mei, mi.Float(0.5), mi.Point2f(0.3, 0.6), active)
        if ok and (not _tuple(out, 3) or not isinstance(out[0], mi.Vector3f)
                   or not _spectrum(out[1]) or not _float(out[2])):
            _refuse("phase function", name, "sample", out, "a tuple (wo: mi.Vector3f, weight: "
                    "mi.Spectrum, pdf: mi.Float), e.g. return wo, weight, pdf")
    if _defines(plugin, "eval_pdf"):
        wo = dr.normalize(mi.Vector3f(-0.2, 0.1, 0.9))
        ok, out = _call(plugin.eval_pdf, ctx, mei, wo, active)
        if ok and (not _tuple(out, 2) or not _spectrum(out[0]) or not _float(out[1])):
            _refuse("phase function", name, "eval_pdf", out, "a tuple (value: mi.Spectrum, "
                    "pdf: mi.Float), e.g. return value, pdf")
