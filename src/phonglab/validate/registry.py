r"""The plugin kinds phonglab validates, in one sequence, and which kind a plugin is.

:data:`KINDS` is what the command line, the sweep, the conformance tables, the batch runner,
:mod:`phonglab.testing` and the package face iterate: adding a kind is its folder (which
declares a :class:`~.kind.Kind`) and one line here.

Detection (:func:`detect`) decides a plugin's kind from what it is, never by trying to load it
as each kind in turn: a loaded object by its class, an XML file by its root element, a type
name (or a dict's ``type``) by Mitsuba's plugin registry (``PluginManager.plugin_type``: a
C++ plugin's ``ObjectType``), or, for a Python plugin (whose type Mitsuba reports as
``Unknown``), by the registration call that registered it: the ``--plugin`` files' recorded
calls, phonglab's own plugins (:data:`phonglab.registration.PLUGINS`).  Importing this module
imports no Mitsuba; :func:`detect` needs the variant set.
"""

from __future__ import annotations

from dataclasses import replace

from . import bsdf, emitter, integrator, medium, phase
from .inputs import xml_root_tag
from .kind import Kind, ValidateError

#: Every plugin kind, in the order the command line's help lists them.
KINDS: tuple[Kind, ...] = (bsdf.KIND, emitter.KIND, integrator.KIND, phase.KIND, medium.KIND)

#: The kind whose table ``phonglab validate --all-builtins`` runs, and that of a table's JSON
#: whose options name no kind (docs/conformance.json, written before the tables named theirs).
DEFAULT = bsdf.KIND


def by_name(name: str) -> Kind:
    """The kind called ``name`` ("bsdf", "emitter", ...)."""
    for k in KINDS:
        if k.name == name:
            return k
    raise ValueError(f"unknown kind {name!r}; choose one of {', '.join(names())}")


def names() -> tuple[str, ...]:
    return tuple(k.name for k in KINDS)


def catalogue(name: str):
    """The conformance table (:class:`~.conformance.Catalogue`) of the kind called ``name``,
    with its kind (the table's part cannot reach its own record)."""
    kind = by_name(name)
    return replace(kind.part("catalogue")(), kind=kind)


def every_topic() -> tuple[str, ...]:
    """Every kind's topics, each once, in the kinds' order."""
    return tuple(dict.fromkeys(t for k in KINDS for t in k.topics))


def accepted() -> str:
    """"a BSDF, an emitter, an integrator or ...": the kinds as one phrase."""
    words = [f"{k.article} {k.word}" for k in KINDS]
    return ", ".join(words[:-1]) + f" or {words[-1]}"


def detect(spec, registered=()) -> Kind:
    """The kind of ``spec`` (a loaded object, an XML file, a type name or a dict with
    ``type``); ``registered``: the (kind word, name) pairs the ``--plugin`` files registered.
    Raises :class:`ValidateError` with one sentence when ``spec`` is none of :data:`KINDS`."""
    import mitsuba as mi   # lazy: the command line checks its input before Mitsuba loads

    for k in KINDS:
        if isinstance(spec, getattr(mi, k.class_name)):
            return k
    if isinstance(spec, str) and spec.endswith(".xml"):
        tag = xml_root_tag(spec)
        for k in KINDS:
            if tag == k.tag:
                return k
        what = f"holds a <{tag}>" if tag else "holds no XML element"
        raise ValidateError(f"{spec} {what}; validate takes an XML file holding one "
                            f"{' or '.join(f'<{k.tag}>' for k in KINDS)}")
    name = spec.get("type") if isinstance(spec, dict) else spec
    if not isinstance(name, str):
        raise ValidateError(f"give a plugin type name, a dict with 'type', an XML file or a "
                            f"loaded plugin ({accepted()}), not a {type(spec).__name__}")
    mine = [word for word, n in registered if n == name]
    for k in KINDS:
        if k.word in mine:
            return k
    object_type = mi.PluginManager.instance().plugin_type(name)
    for k in KINDS:
        if object_type == getattr(mi.ObjectType, k.object_type):
            return k
    from ..registration import PLUGINS
    for _, plugin, kind in PLUGINS:
        if plugin == name:
            return by_name(kind)
    if object_type == mi.ObjectType.Unknown and registered:
        words = list(dict.fromkeys(word for word, _ in registered))
        raise ValidateError(f"cannot load {' or '.join(words)} {name!r} (no plugin has that "
                            f"name); the plugin files registered "
                            f"{', '.join(repr(n) for _, n in registered)}")
    if object_type != mi.ObjectType.Unknown:
        raise ValidateError(f"{name!r} is a Mitsuba {str(object_type).split('.')[-1]} plugin; "
                            f"validate takes {accepted()}")
    return _registered_elsewhere(mi, name)


def _registered_elsewhere(mi, name: str) -> Kind:
    """A Python plugin registered outside the ``--plugin`` files (by the caller's own code
    before it called the validator): Mitsuba keeps no record of its class, so it is built once
    with its defaults and its class read."""
    try:
        obj = mi.load_dict({"type": name})
    except Exception:
        raise ValidateError(f"unknown plugin type {name!r}; name {accepted()} that Mitsuba "
                            f"or phonglab ships, or register it with --plugin FILE.py") from None
    for k in KINDS:
        if isinstance(obj, getattr(mi, k.class_name)):
            return k
    raise ValidateError(f"{name!r} is a {type(obj).__name__}; validate takes {accepted()}")
