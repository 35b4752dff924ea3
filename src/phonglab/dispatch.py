r"""Plugins called the way Mitsuba calls them, and a plugin's own errors told as the plugin's.

Mitsuba's C++ code calls every plugin method virtually.  For a plugin written in Python the
call lands in the kind's trampoline (``PyBSDF``, ``PyPhaseFunction``, ``PyEmitter``,
``PySamplingIntegrator`` in ``src/render/python/*_v.cpp`` at v3.9.1), which

* passes every argument positionally, ``active`` included
  (``NB_OVERRIDE_PURE(sample, ctx, si, sample1, sample2, active)``): a Python method may
  declare ``active`` without a default, as Mitsuba's tutorial does, and is always given it;
* casts what the Python method returns to the C++ return type: a Python number or a
  ``mi.Float`` becomes a ``Spectrum`` (broadcast over the channels), a tuple a ``std::pair``,
  a ``mi.Vector3f`` radiance a ``Spectrum``; a return it cannot cast fails with nanobind's
  ``std::bad_cast``.

Calling the method through the base class's binding -- ``mi.BSDF.eval(plugin, ctx, si, wo,
active)`` -- enters the same virtual call, so a Python plugin goes through its trampoline
and a built-in through its C++ code: what :func:`view` returns is what a Mitsuba integrator
would get.  Which methods go through the binding (those the trampoline forwards) is named by
the caller: each kind's folder of :mod:`phonglab.validate` gives the list of its class.  Every
probe and topic of ``phonglab validate`` calls plugins through these views, never through the
Python methods directly.

Errors.  An exception raised inside the plugin's Python code comes back through the
trampoline with its type and traceback; :func:`origin` finds the innermost frame of that
traceback in the plugin's own file (not in phonglab, Mitsuba, Dr.Jit, numpy or the standard
library) and :func:`describe` words it as the plugin's: ``NameError: name 'x' is not
defined (my_bsdf.py:41, in eval)``.  Dr.Jit's wrapper for an exception raised inside a
custom operation or a symbolic loop ("error while performing a custom differentiable
operation. (see above)") is unwrapped to the plugin's own exception (its ``__cause__``).  A
method the plugin leaves unimplemented (``raise NotImplementedError``) is "not implemented:
<method>" (:func:`not_implemented`, :func:`describe`), never a physics failure.
"""

from __future__ import annotations

import functools
import os
import sys
import sysconfig
import traceback

from .runtime import PluginExited

__all__ = ["Dispatched", "describe", "exit_call", "is_bad_cast", "raised_in", "not_implemented",
           "origin", "root_cause", "view"]


class Dispatched:
    """``plugin`` seen through its base class ``base``: the query ``methods`` go through the base
    class's binding (``active`` passed, returns cast as Mitsuba casts them); every other
    attribute (``flags``, ``component_count``, ``traverse`` ...) is the plugin's own."""

    __slots__ = ("plugin", "base", "_methods")

    def __init__(self, plugin, base, methods):
        object.__setattr__(self, "plugin", plugin)
        object.__setattr__(self, "base", base)
        object.__setattr__(self, "_methods", tuple(methods))

    def __getattr__(self, name):
        if name in self._methods:
            return functools.partial(getattr(self.base, name), self.plugin)
        return getattr(self.plugin, name)

    def __repr__(self) -> str:
        return f"Dispatched({self.plugin!r} as mi.{self.base.__name__})"


def view(plugin, base, methods) -> Dispatched:
    """``plugin`` as Mitsuba calls it: ``methods`` (the query methods the trampoline of
    ``base``, a Mitsuba class, forwards to a Python plugin; each kind's folder names its own)
    through ``base``'s binding.  A view is returned as it is."""
    return plugin if isinstance(plugin, Dispatched) else Dispatched(plugin, base, methods)


# ----------------------------------------------------------------------------- errors
def _library_roots() -> tuple[str, ...]:
    """Folders whose frames are never the plugin's: phonglab, Mitsuba, Dr.Jit, numpy and the
    standard library (a plugin installed as a package of its own is still the plugin's)."""
    here = os.path.dirname(os.path.abspath(__file__))
    paths = sysconfig.get_paths()
    roots = {here, paths.get("stdlib", ""), paths.get("platstdlib", "")}
    for mod in ("mitsuba", "drjit", "numpy"):
        m = sys.modules.get(mod)
        if m is not None and getattr(m, "__file__", None):
            roots.add(os.path.dirname(os.path.abspath(m.__file__)))
    return tuple(sorted(r for r in roots if r))


def _plugin_frame(fs) -> bool:
    name = fs.filename
    if name.startswith("<") and not name.startswith("<plugin"):
        return False
    path = os.path.abspath(name)
    return not any(path == r or path.startswith(r + os.sep) for r in _library_roots())


def root_cause(exc: BaseException) -> BaseException:
    """The plugin's own exception behind Dr.Jit's wrappers: a ``RuntimeError`` or
    ``Exception`` whose message says "(see above)" or "custom differentiable operation" and
    whose ``__cause__`` is set is replaced by that cause, recursively."""
    seen = set()
    while id(exc) not in seen:
        seen.add(id(exc))
        cause = exc.__cause__ or (exc.__context__ if not exc.__suppress_context__ else None)
        text = str(exc)
        if cause is None or not ("see above" in text or "custom differentiable" in text
                                 or "dr.while_loop" in text or "symbolic" in text):
            return exc
        exc = cause
    return exc


def origin(exc: BaseException) -> tuple[str, int, str] | None:
    """(file, line, function) of the innermost frame of ``exc``'s traceback that lies in the
    plugin's own code, or None (a built-in's error, or the validator's own)."""
    for fs in reversed(traceback.extract_tb(exc.__traceback__)):
        if _plugin_frame(fs):
            return fs.filename, fs.lineno or 0, fs.name
    return None


def not_implemented(exc: BaseException) -> str | None:
    """The plugin method left unimplemented, when ``exc`` is a ``NotImplementedError`` raised
    in the plugin's own code (its function's name), else None."""
    exc = root_cause(exc)
    if not isinstance(exc, NotImplementedError):
        return None
    where = origin(exc)
    return where[2] if where is not None else None


def is_bad_cast(exc: BaseException) -> bool:
    """Whether ``exc`` is the trampoline refusing a return it cannot cast to Mitsuba's type
    (nanobind's ``std::bad_cast``, raised after the plugin's code returned: no frame of the
    plugin's own in its traceback)."""
    return "bad_cast" in str(exc) and origin(exc) is None


def raised_in(exc: BaseException, files) -> str | None:
    """:func:`describe` of ``exc`` when its innermost plugin frame (Dr.Jit's wrappers
    unwrapped) lies in one of ``files`` (a user's ``--plugin`` files), else None."""
    where = origin(root_cause(exc))
    if where is None:
        return None
    for f in files:
        try:
            if os.path.samefile(where[0], f):
                return describe(exc)
        except OSError:
            continue
    return None


def exit_call(exc: BaseException) -> str | None:
    """``the plugin called sys.exit(0) (my_bsdf.py:12, in eval)`` when ``exc`` (or what
    Dr.Jit wrapped) is a ``SystemExit`` or an intercepted ``os._exit``
    (:class:`phonglab.runtime.PluginExited`); "sys.exit(0) was called" where no frame of a
    plugin is in its traceback; None for any other exception."""
    exc = root_cause(exc)
    if isinstance(exc, PluginExited):
        call = f"os._exit({exc.status!r})"
    elif isinstance(exc, SystemExit):
        call = f"sys.exit({exc.code!r})"
    else:
        return None
    where = origin(exc)
    if where is None:
        return f"{call} was called"
    return f"the plugin called {call} ({os.path.basename(where[0])}:{where[1]}, in {where[2]})"


def describe(exc: BaseException) -> str:
    """One line: the plugin's own exception and where in its file it was raised,
    ``NameError: name 'x' is not defined (my_bsdf.py:41, in eval)``; "not implemented:
    <method> (file:line)" for a ``NotImplementedError``."""
    exc = root_cause(exc)
    where = origin(exc)
    text = str(exc).strip()
    first = text.splitlines()[0] if text else ""
    at = ""
    if where is not None:
        at = f" ({os.path.basename(where[0])}:{where[1]}, in {where[2]})"
    if isinstance(exc, NotImplementedError) and where is not None:
        return f"not implemented: {where[2]}{at}" + (f": {first}" if first else "")
    return f"{type(exc).__name__}: {first or '(no message)'}{at}"
