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

Only Python-defined methods are called (:func:`defines`: a built-in's C++ methods return their
own types), and an exception inside the call is left to the topics, which report it as the
plugin's error.  Each kind's ``returns`` part (:mod:`phonglab.validate.kind`) names its methods,
the arguments of one lane and what Mitsuba expects, and calls :func:`checked` for each; these
are the helpers they share.
"""

from __future__ import annotations

import drjit as dr

from .. import dispatch, runtime
from . import timeout
from .kind import ValidateError

__all__ = ["call", "checked", "defines", "refuse", "sequence", "what"]


def defines(plugin, name: str) -> bool:
    """Whether ``plugin``'s class defines ``name`` in Python (not a Mitsuba built-in's)."""
    return any(name in cls.__dict__ for cls in type(plugin).__mro__
               if not cls.__module__.startswith(("mitsuba", "drjit", "builtins", "nanobind")))


def what(value) -> str:
    """What a value is, in a few words: ``a tuple of 2 (Color3f, Bool)``, ``Color3f``."""
    if isinstance(value, (tuple, list)):
        inner = ", ".join(type(v).__name__ for v in value[:4]) + (", ..." if len(value) > 4 else "")
        return f"a {type(value).__name__} of {len(value)} ({inner})"
    return type(value).__name__


def refuse(word, name, method, value, expects):
    """Raise the one sentence: ``method`` of the ``word`` ``name`` returned ``value``, which
    Mitsuba cannot take; it expects ``expects``."""
    raise ValidateError(f"{method}() of the {word} {name!r} returned {what(value)}, which "
                        f"Mitsuba cannot take: it expects {expects}; fix the return statement "
                        f"(checked on one lane, as Mitsuba's trampoline casts it)")


def call(method, *args):
    """(True, the return) or (False, the exception) of one call; the topics report a
    plugin's exception as its error (a ``sys.exit``/``os._exit`` too, as a failing row), so it
    is not bad input here."""
    try:
        with runtime.exits_intercepted(), timeout.within_topic_limit():
            return True, method(*args)
    except (Exception, timeout.TopicTimeout, SystemExit, runtime.PluginExited) as exc:
        return False, exc


def checked(view: dispatch.Dispatched, word, name, method, args, expects):
    """Call ``method`` of the plugin through Mitsuba's dispatch (``view``: the plugin as its
    kind's binding calls it, :func:`phonglab.dispatch.view`); where the trampoline cannot cast
    what the Python method returned, say what that was (the method called directly) and refuse
    it."""
    ok, out = call(getattr(view, method), *args)
    try:
        if ok or not dispatch.is_bad_cast(out):
            return
        ok, raw = call(getattr(view.plugin, method), *args)
        refuse(word, name, method, raw if ok else out, expects)
    finally:
        # an exception held here holds its traceback, whose frames hold this one: a cycle
        # that keeps the plugin instance alive until the garbage collector runs, and Dr.Jit
        # traces every live instance in each later symbolic call (a render of another
        # scene then ran the plugin's eval: a hanging one forever)
        out = raw = None


def sequence(out, n: int) -> bool:
    """Whether ``out`` is a Python tuple or list of ``n`` (not a Dr.Jit array of n channels)."""
    return isinstance(out, (tuple, list)) and not isinstance(out, dr.ArrayBase) and len(out) == n
