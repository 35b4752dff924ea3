r"""What a run is given, loaded: the variant set, the user's plugin files (``--plugin
FILE.py``) run with what each registers recorded, and the plugin loaded -- everything that can
be bad input, each one sentence (:class:`~.inputs.ValidateError`) before any check runs.

* :func:`start`: the variant (phonglab's plugins registered in it);
* :func:`load_plugins`: every command that takes ``--plugin`` runs the files here:
  ``phonglab validate`` (through :mod:`.pipeline`), ``check``, ``fit`` and ``render`` (in each
  variant it sets, :func:`phonglab.registration.plugin_files`).  A file is run with Mitsuba's
  registration calls (:data:`REGISTER_CALLS`) wrapped, so that what it registers is known as
  (kind word, name) pairs (:class:`Registered`), from which the validator detects a Python
  plugin's kind (:func:`phonglab.validate.registry.detect`) and checks that every file
  registered a plugin of the kind it validates (:func:`check_registered`); a name Mitsuba or
  phonglab already has is refused before it is registered (:func:`taken_by`: the report would
  be of the plugin that name already meant, not of the file's); a file that exits
  (``sys.exit``, ``os._exit``), switches the variant or runs past the time limit
  (:mod:`.timeout`) is one sentence, never the process's end, a hang or a report of nothing;
* :func:`load`: the plugin from a type name, a dict for ``mi.load_dict``, an XML file or a
  loaded object (:func:`phonglab.settings.load_plugin`, or the kind's own ``load`` part), its
  ``traverse()`` and the returns of its Python methods checked (the kind's ``returns`` part);
* :func:`prepare`: the three for a plugin of a given kind (a sweep point's worker,
  :func:`phonglab.validate.sweep.run_point`).
"""

from __future__ import annotations

import runpy
from pathlib import Path

import mitsuba as mi

from .. import dispatch, registration, runtime
from ..settings import Loaded, PluginError, load_plugin
from . import timeout
from .inputs import ValidateError, check_plugin_file
from .kind import Kind
from .registry import KINDS

__all__ = ["REGISTER_CALLS", "Registered", "check_registered", "load", "load_plugins", "prepare",
           "start", "taken_by"]


#: Mitsuba's registration calls a plugin file may make, and the word of what each registers:
#: each kind's (:attr:`~.kind.Kind.register`, e.g. ``mi.register_<kind>``) and those of the
#: plugin types no kind validates.
REGISTER_CALLS = {**{k.register.removeprefix("mi."): k.word for k in KINDS},
                  "register_texture": "texture", "register_sensor": "sensor",
                  "register_film": "film", "register_shape": "shape",
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
        by_file[str(p)] = _run(path, kind)
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


def _run(path: Path, kind: Kind | None) -> list[tuple[str, str]]:
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
    variant, limit = mi.variant(), timeout.limit()
    try:
        with runtime.exits_intercepted(), timeout.alarm(limit):
            runpy.run_path(str(path), run_name="__phonglab_plugin__")
    except Collision as exc:
        raise ValidateError(str(exc)) from None
    except (SystemExit, runtime.PluginExited) as exc:
        call = (f"os._exit({exc.status!r})" if isinstance(exc, runtime.PluginExited)
                else f"sys.exit({exc.code!r})")
        raise ValidateError(f"plugin file {str(path)!r} called {call} while it was loaded, so "
                            f"nothing was judged; a plugin file must only define its plugin "
                            f"and call {register_call}") from None
    except timeout.TopicTimeout:
        raise ValidateError(f"plugin file {str(path)!r} did not finish loading within "
                            f"{limit:g} s (stopped by the timeout: does it loop forever at "
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
    limit = timeout.limit()
    try:
        with timeout.alarm(limit) as state:  # the constructor, traverse(), each method once
            try:
                if own is not None:
                    loaded = own(spec, params, hint)
                else:
                    loaded = load_plugin(spec, params, kind=getattr(mi, kind.class_name),
                                         word=kind.word, hint=hint)
            except PluginError as exc:
                if state["fired"]:       # Mitsuba's loader quoted the timeout as text
                    raise timeout.TopicTimeout() from None
                raise ValidateError(str(exc)) from exc
            _check_traverse(kind, loaded)
            returns = kind.part("returns")   # the Python methods' return types, on one lane
            if returns is not None:
                returns(loaded.plugin, loaded.label)
    except timeout.TopicTimeout:
        name = f" {spec!r}" if isinstance(spec, str) else ""
        raise ValidateError(f"loading the {kind.word}{name} (its constructor, "
                            f"traverse() and one call of each method) did not finish within "
                            f"{limit:g} s (stopped by the timeout: does the plugin's Python code "
                            f"loop forever?)") from None
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
