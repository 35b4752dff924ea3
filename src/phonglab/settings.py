r"""``NAME=VALUE`` settings and plugins loaded from them: the one parser, the one loader.

Grammar of a ``--set NAME=VALUE`` (``phonglab validate``, ``phonglab fit``), as
:func:`parse_sets` reads it into the parameters of a ``mi.load_dict`` dictionary:

* ``NAME`` is a parameter name, or dotted names for a nested object:
  ``--set bsdf.type=diffuse --set bsdf.reflectance=0.3`` gives
  ``{"bsdf": {"type": "diffuse", "reflectance": 0.3}}`` (``twosided``, ``mask``, ``bumpmap``,
  ...); a texture parameter is set the same way (``--set reflectance.type=checkerboard``).
  Each part is a Python-style identifier (letters, digits, ``_``; not starting with a digit).
* ``VALUE``, surrounding blanks ignored, is the first that applies of

  - ``true`` / ``false`` (any case)                    -> bool;
  - numbers separated by commas: three                 -> ``{"type": "rgb", "value": [r, g, b]}``
    (an ``r, g, b`` colour; every component finite), any other count -> an error;
  - an integer literal (``3``, ``-2``)                 -> int;
  - a number (``0.25``, ``1e-3``; finite)              -> float;
  - anything else                                      -> str (``distribution=ggx``, a filename).

Mitsuba takes an int wherever a float is expected (``alpha=1`` loads as α = 1.0), except an
index of refraction: ``lookup_ior`` (``include/mitsuba/render/ior.h:79-94``) reads ``int_ior``
and ``ext_ior`` as a number only when their type is Float and otherwise as a material name, so
an integer there fails to load ("expected string, got integer"); an integer literal given to a
name in :data:`IOR_NAMES` is read as a float (``int_ior=3`` -> 3.0).  A scene's
``<default>`` parameters (``phonglab render -D NAME=VALUE``) are split by the same
:func:`split` but keep their value as text: Mitsuba substitutes it into the XML.

:func:`load_plugin` builds one plugin of an expected kind (``mi.BSDF`` today; an emitter or an
integrator the same way) from a type name, a ``mi.load_dict`` dictionary, an XML file holding
that one object, or an already loaded object.  Bad input is one sentence
(:class:`ParameterError`, :class:`PluginError`).

Importing this module does not import Mitsuba (the command line parses ``--set`` first);
:func:`load_plugin` does, in the variant already set.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any, NamedTuple

from .errors import PhonglabError

#: NAME of NAME=VALUE: identifiers joined by dots.
_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*$")
#: An integer literal.
_INT = re.compile(r"[+-]?\d+")
#: The example every NAME=VALUE message ends with.
#: Parameters Mitsuba reads with ``lookup_ior`` (a Float or a material name, never an integer).
IOR_NAMES = frozenset({"int_ior", "ext_ior"})

EXAMPLE = "--set alpha=0.2 or --set reflectance=0.2,0.3,0.4"


class ParameterError(PhonglabError, ValueError):
    """A ``--set`` argument that is not NAME=VALUE with a usable value."""


class PluginError(PhonglabError):
    """A plugin (type name, dictionary, XML file or object) that cannot be loaded as asked."""


#: Seeds phonglab takes: Mitsuba's 32-bit unsigned seed.  A render's pass k uses
#: (seed·1_000_003 + k) mod 2³² (:func:`phonglab.engine.render.pass_seed`), a bijection of the seeds
#: in this range for each k (1_000_003 is odd); seeds outside it would alias silently
#: (-1 and 2³² − 1 render the same image), so they are refused.
SEED_MAX = (1 << 32) - 1


def check_seed(seed) -> int:
    """``seed`` as an int in [0, :data:`SEED_MAX`], else :class:`ParameterError`."""
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed <= SEED_MAX:
        raise ParameterError(f"the seed must lie in 0..{SEED_MAX} (Mitsuba's 32-bit seed), "
                             f"got {seed!r}")
    return seed


def check_max_seconds(seconds, option: str = "--max-seconds") -> float:
    """A time limit as a float > 0 (``inf``: none), else :class:`ParameterError`: a negative,
    zero or NaN limit would refuse every plan, after its pilot."""
    if (isinstance(seconds, bool) or not isinstance(seconds, (int, float))
            or not seconds > 0):
        raise ParameterError(f"{option} must be a positive number of seconds ('inf' for no "
                             f"limit), got {seconds!r}")
    return float(seconds)


def split(text: str) -> tuple[str, str] | None:
    """``NAME=VALUE`` -> (NAME, VALUE) as written (split at the first ``=``); None when there
    is no ``=`` or no name before it."""
    name, sep, value = text.partition("=")
    return (name, value) if sep and name else None


def _numbers(parts: list[str]) -> list[float] | None:
    try:
        return [float(p) for p in parts]
    except ValueError:
        return None


def parse_value(text: str):
    """One VALUE of the grammar in the module docstring; :class:`ParameterError` when unusable."""
    t = text.strip()
    if t.lower() in ("true", "false"):
        return t.lower() == "true"
    parts = t.split(",")
    if len(parts) > 1:
        numbers = _numbers(parts)
        if numbers is None:
            return t
        if len(numbers) != 3:
            raise ParameterError(f"the value {text!r} has {len(numbers)} numbers; give one "
                                 f"number or three (an 'r, g, b' colour)")
        if not all(math.isfinite(x) for x in numbers):
            raise ParameterError(f"the colour {text!r} has a non-finite component; give three "
                                 f"finite numbers like 0.2,0.3,0.4")
        return {"type": "rgb", "value": numbers}
    if _INT.fullmatch(t):
        return int(t)
    try:
        x = float(t)
    except ValueError:
        return t
    if not math.isfinite(x):
        raise ParameterError(f"the value {text!r} is not finite; give a finite number")
    return x


def parse_sets(items) -> dict:
    """NAME=VALUE strings -> a (nested) parameter dict; :class:`ParameterError` on bad input.

    A later setting of the same name replaces an earlier one.
    """
    out: dict = {}
    for item in items or ():
        pair = split(item)
        name = pair[0].strip() if pair else ""
        if not pair or not _NAME.match(name) or pair[1].strip() == "":
            raise ParameterError(f"--set expects NAME=VALUE, and {item!r} is not NAME=VALUE; "
                                 f"write e.g. {EXAMPLE}")
        *path, leaf = name.split(".")
        if path and leaf == "value" and "type" not in _at(out, path):
            # NAME.value: mi.traverse's key of a constant texture, i.e. NAME itself (a
            # colour stays one {"type": "rgb"} node, not a node wrapped in another)
            *path, leaf = path
        node = out
        for key in path:
            child = node.setdefault(key, {})
            if not isinstance(child, dict):
                raise ParameterError(f"--set {item!r}: {key} already has a value, so it cannot "
                                     f"also hold {leaf}; set {key}.type=... instead")
            node = child
        if isinstance(node.get(leaf), dict):
            raise ParameterError(f"--set {item!r}: {name} is a nested object already; set its "
                                 f"fields ({name}.NAME=VALUE) instead")
        value = parse_value(pair[1])
        if leaf in IOR_NAMES and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        node[leaf] = value
    return out


def _at(out: dict, path: list[str]) -> dict:
    """The node ``out`` holds at ``path`` so far ({} where there is none yet)."""
    node = out
    for key in path:
        node = node.get(key) if isinstance(node, dict) else None
        if not isinstance(node, dict):
            return {}
    return node


_UNREFERENCED = re.compile(r'unreferenced propert(?:y|ies) in (\w+) plugin of type "([^"]+)"')
_UNREFERENCED_NAME = re.compile(r'^\s*-\s*\w+\s+"([^"]+)"', re.MULTILINE)


def unread_parameters(text: str) -> tuple[str, str, list[str]] | None:
    """(kind, plugin type, parameter names) of Mitsuba's "Found N unreferenced properties in
    <kind> plugin of type "T": - <type> "<name>": <value> ..." in ``text`` (the kind is
    "unknown" for a Python plugin), else None."""
    m = _UNREFERENCED.search(text)
    if not m:
        return None
    return m.group(1), m.group(2), _UNREFERENCED_NAME.findall(text)


def _exit_in_traceback(text: str) -> str | None:
    """"the plugin called sys.exit(0) (file.py:11, in __init__)" when the Python traceback
    Mitsuba's loader quotes in ``text`` ends in a ``SystemExit`` or an intercepted
    ``os._exit`` (:class:`phonglab.runtime.PluginExited`), else None."""
    tail = text.rpartition("Traceback (most recent call last):")[2].strip().splitlines()
    last = re.match(r"(SystemExit|PluginExited)(?::\s*(.*))?$", tail[-1].strip()) if tail else None
    if not last:
        return None
    call = f"{'sys.exit' if last.group(1) == 'SystemExit' else 'os._exit'}({last.group(2) or ''})"
    frames = [f for f in re.findall(r'File "([^"]+)", line (\d+), in (\S+)', "\n".join(tail))
              if Path(f[0]).name != "runtime.py"]      # the os._exit replacement's own frame
    where = f" ({Path(frames[-1][0]).name}:{frames[-1][1]}, in {frames[-1][2]})" if frames else ""
    return f"the plugin called {call}{where}: a plugin must return or raise, never end the process"


def mitsuba_reason(exc: Exception) -> str:
    """The informative part of a Mitsuba loader error, on one line (source tags and the
    "While loading dictionary node" prefix dropped, the innermost cause kept).

    Mitsuba's "Found 2 unreferenced properties in ... plugin of type "mybp": - rgb
    "diffuse_reflectance": [0.5, 0.5, 0.5] ..." is said as what it means, the plugin does
    not read those parameters; a value's brackets are never taken for a cause's tag (that
    cut the sentence to "0.5, 0.5, 0.5]")."""
    raw = str(exc)
    unread = unread_parameters(raw)
    if unread:
        _, plugin_type, names = unread
        return (f"the plugin {plugin_type!r} does not read "
                + (f"the parameter{'s' if len(names) > 1 else ''} {', '.join(names)}" if names
                   else "a parameter it was given")
                + "; Mitsuba refuses a parameter the plugin never reads")
    text = " ".join(raw.split())
    text = re.sub(r"\[[\w.]+:\d+\] ", "", text)              # [parser.cpp:444] source tags
    text = re.sub(r"^(While loading|At) dictionary node \"root\": ", "", text)
    text = re.split(r": \[(?=[A-Za-z_][\w.]*\] )", text)[-1]   # the innermost cause's tag
    text = re.sub(r"^([A-Za-z_][\w.]*)\] ", r"\1: ", text)     # [PluginManager] -> its name
    if "Traceback (most recent call last):" in text:           # a Python plugin raised:
        head, _, tail = text.partition("Traceback (most recent call last):")
        exited = _exit_in_traceback(raw)
        if exited:
            return head + exited
        frames = re.findall(r"\b\w+(?:Error|Exception): .*", tail)   # keep its last line
        text = head + (frames[-1] if frames else tail.strip())
    text = text.strip().rstrip(".!")
    return text or f"{type(exc).__name__} without a message"


class Loaded(NamedTuple):
    """A plugin :func:`load_plugin` built, with how to name and describe it."""

    plugin: Any              #: the loaded object (an instance of the expected kind)
    label: str               #: its type name (or the XML file's name, or its class name)
    spec: dict | None        #: the description for a report's meta (None for a given object)
    #: the ``--plugin`` files run before it was loaded (a topic that loads it again elsewhere,
    #: in another variant or process, runs them there too)
    files: tuple = ()
    #: where a loaded object came from (``{"file": scene, "id": ID}``: a scene's material),
    #: None when its spec says it
    origin: dict | None = None


def _describe(d: dict) -> dict:
    return {k: (v if isinstance(v, (int, float, str, bool)) else repr(v)) for k, v in d.items()}


def load_plugin(spec, params: dict | None = None, *, kind: type, word: str,
                hint: str = "check the type name and --set values") -> Loaded:
    """Load one plugin of class ``kind`` (e.g. ``mi.BSDF``) from ``spec``.

    ``spec``: a plugin type name, a ``mi.load_dict`` dictionary with ``"type"``, the path of an
    XML file (``.xml``) holding one such object, or an object already loaded.  ``params``
    (e.g. from :func:`parse_sets`) are added to a name's or dictionary's parameters; they
    cannot change a file or an object.  ``word`` names the kind in messages (``"BSDF"``),
    ``hint`` is the fix a failing ``mi.load_dict`` message ends with.  Raises
    :class:`PluginError` with one sentence; Mitsuba's variant must be set.
    """
    import mitsuba as mi   # lazy: the command line parses its settings before Mitsuba loads

    if isinstance(spec, kind):
        if params:
            raise PluginError(f"parameters cannot be set on an already loaded {word}; pass its "
                              f"type name or dict instead")
        return Loaded(spec, spec.class_().name() if hasattr(spec, "class_")
                      else type(spec).__name__, None)
    if isinstance(spec, (str, Path)) and str(spec).endswith(".xml"):
        return _load_xml(mi, str(spec), params, kind, word)
    if isinstance(spec, str):
        spec = {"type": spec}
    if not isinstance(spec, dict) or "type" not in spec:
        raise PluginError(f"give a {word} plugin type name, a dict with 'type', an XML file or "
                          f"an mi.{kind.__name__}")
    d = {**spec, **(params or {})}
    _check_bitmaps(d, word, spec["type"])
    try:
        plugin = mi.load_dict(d)
    except Exception as exc:   # Mitsuba reports unknown plugins/parameters as RuntimeError
        raise PluginError(f"cannot load {word} {spec['type']!r} ({mitsuba_reason(exc)}); "
                          f"{hint}") from exc
    if not isinstance(plugin, kind):
        raise PluginError(f"{spec['type']!r} is a {type(plugin).__name__}, not a {word} "
                          f"plugin; name a {word} plugin type")
    return Loaded(plugin, spec["type"], _describe(d))


def _check_bitmaps(d: dict, word: str, type_name: str, path: str = "") -> None:
    """A ``bitmap`` node with none of ``filename``, ``data``, ``bitmap`` is refused before
    Mitsuba sees it: Mitsuba 3.9.1's bitmap texture crashes the process (SIGSEGV, exit 139) loading one
    (``mi.load_dict({"type": "bitmap"})``), where a missing file is an ordinary error."""
    for key, v in d.items():
        if isinstance(v, dict):
            _check_bitmaps(v, word, type_name, f"{path}{key}.")
    if d.get("type") == "bitmap" and not {"filename", "data", "bitmap"} & set(d):
        where = path.rstrip(".") or "it"
        raise PluginError(f"cannot load {word} {type_name!r}: the bitmap texture {where} has no "
                          f"filename (Mitsuba 3.9.1 crashes loading a bitmap without one); give "
                          f"--set {path}filename=PATH.png, or a value for a constant texture")


def _load_xml(mi, name: str, params, kind: type, word: str) -> Loaded:
    path = Path(name)
    if not path.is_file():
        raise PluginError(f"XML file {name!r} does not exist")
    if params:
        raise PluginError(f"--set cannot change an XML file's {word}; edit the file instead")
    try:
        plugin = mi.load_string(path.read_text())
    except Exception as exc:
        raise PluginError(f"{path.name} does not load as one <{word.lower()}>: "
                          f"{mitsuba_reason(exc)}") from exc
    if not isinstance(plugin, kind):
        raise PluginError(f"{path.name} holds a {type(plugin).__name__}, not one "
                          f"<{word.lower()}>")
    return Loaded(plugin, path.name, {"file": str(path)})
