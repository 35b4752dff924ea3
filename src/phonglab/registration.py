"""Registering phonglab's Mitsuba plugins for the active variant, and keeping them registered.

Mitsuba keeps one plugin table per variant, and a Python plugin class derives
from the variant's ``mi.BSDF``/``mi.SamplingIntegrator``.  :func:`register`
therefore (re)builds each plugin module for the active variant and registers
it; a variant callback repeats this after every later ``mi.set_variant``
(the pattern of Mitsuba's own ``python/ad/integrators``).  It also makes every
``params.update()`` transactional across objects (:mod:`phonglab.transactions`): a plugin
that refuses its new values leaves the update's other objects as they were.

Mitsuba is imported inside the functions: ``import phonglab`` imports this module, and it must
neither load Mitsuba (about half a second for every ``phonglab`` command, ``--help`` included)
nor let Dr.Jit start before :mod:`phonglab.runtime` has pinned libLLVM.
"""

from __future__ import annotations

import contextlib
import importlib
import threading
from typing import Callable

from . import runtime, transactions

#: (module of phonglab.plugins, name in scene files, kind)
PLUGINS: list[tuple[str, str, str]] = [
    ("lambert", "lambert", "bsdf"),
    ("phong", "phong", "bsdf"),
    ("whitted", "whitted", "integrator"),
]

_lock = threading.Lock()
_registered: set[str] = set()          # variants in which every plugin is registered
_classes: dict[tuple[str, str], type] = {}   # (module, variant) -> plugin class
_callback_installed = False
#: A user's own plugin files (``phonglab render --plugin``) and what runs them, run once in each
#: variant :func:`register` activates, since a Python plugin class derives from its variant's
#: classes (:func:`plugin_files`).
_user_files: tuple[str, ...] = ()
_user_load: Callable | None = None
_user_variants: set[str] = set()


def plugin_class(name: str, variant: str) -> type:
    """The class of plugin module ``name`` built against ``variant`` (cached)."""
    key = (name, variant)
    if key not in _classes:
        module = importlib.import_module(f"phonglab.plugins.{name}")
        if getattr(module, "_built_for_variant", variant) != variant:
            module = importlib.reload(module)
        module._built_for_variant = variant
        _classes[key] = module.PLUGIN_CLASS
    return _classes[key]


def _register_active() -> None:
    import mitsuba as mi

    variant = mi.variant()
    if variant is None:
        return
    # Registration is cheap, so it is repeated on every switch rather than trusted to persist.
    for module_name, plugin_name, kind in PLUGINS:
        factory = plugin_class(module_name, variant)
        register_kind = getattr(mi, f"register_{kind}")     # Mitsuba's mi.register_<kind>
        register_kind(plugin_name, lambda props, cls=factory: cls(props))
    _registered.add(variant)


def _on_variant_change(old, new) -> None:
    if new is not None:
        with _lock:
            _register_active()


def register(variant: str | None = None) -> str:
    """Register every phonglab plugin for the active Mitsuba variant.

    Args:
        variant: a Mitsuba variant to set first. When neither this nor an active
            variant exists, ``llvm_ad_rgb`` is set (``scalar_rgb`` with a loud
            :class:`phonglab.runtime.SlowFallbackWarning` when LLVM is unusable).

    Returns:
        the active variant.

    Idempotent; plugins follow every later ``mi.set_variant`` automatically.  Dr.Jit gets
    at least :data:`phonglab.runtime.MIN_KERNEL_THREADS` threads (one hangs Mitsuba's
    OpenEXR I/O: :func:`phonglab.runtime.kernel_threads_floor`).
    """
    global _callback_installed
    import mitsuba as mi

    runtime.configure()
    if variant is not None and variant != mi.variant():
        runtime.set_variant(variant)
    elif mi.variant() is None:
        runtime.set_variant(None)
    runtime.kernel_threads_floor()
    transactions.install()
    with _lock:
        if not _callback_installed:
            mi.detail.add_variant_callback(_on_variant_change)
            _callback_installed = True
        _register_active()
    active = mi.variant()
    if _user_files and active not in _user_variants:
        _user_variants.add(active)
        try:
            _user_load(_user_files)
        except BaseException:
            _user_variants.discard(active)
            raise
    return mi.variant()


@contextlib.contextmanager
def plugin_files(paths, load: Callable):
    """For the block, run the plugin files ``paths`` with ``load`` (each file calls
    ``mi.register_*`` with a name of its own:
    :func:`phonglab.validate.loading.load_plugins`, which refuses a name Mitsuba or
    phonglab has) once in every variant :func:`register` activates, the active one at its next
    call (``phonglab render --plugin``: the scene is loaded, in whatever variant the render or
    its plan chose, with the user's plugins registered there)."""
    global _user_files, _user_load
    previous = _user_files, _user_load, set(_user_variants)
    _user_files, _user_load = tuple(str(p) for p in paths), load
    _user_variants.clear()
    try:
        yield
    finally:
        _user_files, _user_load = previous[:2]
        _user_variants.clear()
        _user_variants.update(previous[2])


def registered_variants() -> frozenset[str]:
    """Variants in which phonglab's plugins are registered (for diagnostics)."""
    return frozenset(_registered)
