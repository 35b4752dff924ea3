"""Scenes: resolving a scene name once, its ``<default>`` parameters, loading with clear errors, inspection.

A scene is given as a path to a Mitsuba XML file or as the name of one of the scenes phonglab
ships (``cornell_phong``); :func:`scene_path` resolves it.  The shipped scenes, and the textures
they name by paths relative to themselves, are package data in ``phonglab/scenes_xml/``, found
through :mod:`importlib.resources`, so an installed phonglab renders them from any working
directory.  :func:`load_scene` registers
phonglab's plugins and loads it, turning Mitsuba's loader errors into one sentence naming the
problem and the fix (:func:`explain_load_error`); XML that does not parse is reported by
:func:`malformed` alone.  :func:`inspect_scene` reads what the file says about colour,
spectral data, delta BSDFs and its integrator without rendering (the planner uses it).
"""

from __future__ import annotations

import difflib
import hashlib
import re
from importlib import resources
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import mitsuba as mi
import numpy as np

from .. import registration
from ..errors import SceneError
from ..runtime import quiet_mitsuba
from ..settings import unread_parameters

#: The shipped scenes.  Mitsuba opens a scene and its textures from the file system, and pip
#: installs a wheel's package data as plain files, so the resource folder is a real folder.
SCENES_DIR = Path(str(resources.files("phonglab") / "scenes_xml"))


def scene_path(name: str | Path) -> Path:
    """Resolve a scene given as a path or as the name of a shipped scene (``cornell_phong``)."""
    p = Path(name)
    if p.is_file():
        return p
    for cand in (SCENES_DIR / p, SCENES_DIR / (str(p) + ".xml")):
        if cand.is_file():
            return cand
    if p.is_dir():
        inside = sorted(p.glob("*.xml"))
        such = f" such as {inside[0]}" if inside else ""
        raise SceneError(f"the scene {name} is a folder; give the path of a Mitsuba XML "
                         f"file{such}")
    raise SceneError(f"scene file not found: {name} (give a path to a Mitsuba XML file, or "
                        f"one of: {', '.join(sorted(q.stem for q in SCENES_DIR.glob('*.xml')))})")


def malformed(where: str, why: str) -> SceneError:
    """The one message for XML that does not parse: where, why, and what to fix."""
    return SceneError(f"{where}: malformed XML ({why}); fix the markup there "
                         f"(an unclosed or mismatched tag, or a stray character).")


def parse_xml(path: str | Path) -> ET.Element:
    """The root element of an XML file; XML that does not parse is a :class:`SceneError`."""
    try:
        return ET.parse(path).getroot()
    except ET.ParseError as exc:
        line = exc.position[0] if exc.position else "?"
        why = re.sub(r":\s*line \d+, column \d+$", "", str(exc))
        raise malformed(f"{path}, line {line}", why) from None


def scene_defaults(path: str | Path) -> dict[str, str]:
    """The ``<default name=... value=...>`` entries of a scene file (its tunable parameters)."""
    root = parse_xml(path)
    return {d.get("name"): d.get("value") for d in root.iter("default") if d.get("name")}


def file_hash(path: Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


_MI_LINE = re.compile(r"\(line (\d+)")
_NOT_FOUND = re.compile(r'instantiate (\w+) plugin of type "([^"]+)".*Plugin "[^"]+" not found')
_PLUGIN_EXCEPTION = re.compile(r"^\w*(?:Error|Exception): ((?:.|\n)*?)\s*$", re.MULTILINE)
_UNPARSABLE = re.compile(r'could not parse (floating point|integer|boolean|\w+) value "([^"]*)"')
_FILE_ERROR = re.compile(r'\[FileStream\] "([^"]+)": (I/O error[^\n]*)')
_INSTANTIATE = re.compile(r'instantiate (\w+) plugin of type "([^"]+)"')
_OUT_OF_RANGE = re.compile(r'Property "(\w+)": value (\S+) is out of bounds, must be in the range '
                           r'\[([^,]+), ([^\]]+)\]')
#: Scene-file names of phonglab's own plugins (whose parameters are all listed by traverse).
_OWN_PLUGINS = ("lambert", "phong")


def _plugin_parameters(plugin_type: str) -> list[str]:
    """XML parameter names of one of phonglab's plugins (its ``traverse`` keys), else []."""
    if plugin_type not in _OWN_PLUGINS:
        return []
    try:
        return sorted({k.split(".")[0] for k in mi.traverse(mi.load_dict({"type": plugin_type})).keys()})
    except Exception:  # the listing is a courtesy; the error message stands without it
        return []


def explain_load_error(path: Path, exc: Exception) -> SceneError:
    """Turn Mitsuba's loader error into one sentence naming the problem and the fix.

    Mitsuba words the cases as (3.9.1, the same for Python and built-in plugins):
    ``While loading F (line L, col C): Found 1 unreferenced property in bsdf plugin of
    type "phong":\n  - float "exponant": 3``; ``Parsing of XML file "F" failed: <why>
    (line L, col C)``; ``failed to instantiate bsdf plugin of type "x": [PluginManager]
    Plugin "x" not found!``; and a Python plugin's own exception with its traceback.
    """
    text = str(exc).strip()
    line_m = _MI_LINE.search(text)
    where = f"{path}, line {line_m.group(1)}" if line_m else str(path)
    # Mitsuba prefixes its messages with "[parser.cpp:444] ..." and may nest a Python traceback.
    core = re.sub(r"^\[[\w.]+:\d+\]\s*", "", text.splitlines()[-1] if text else type(exc).__name__)
    for explain in (_plugin_raised, _unreferenced, _not_found, _unparsable_value, _missing_file,
                    _out_of_range, _unused_parameters):
        message = explain(text, where, path)
        if message:
            return SceneError(message)
    if "Parsing of XML file" in text:
        why = re.sub(r'^Parsing of XML file "[^"]*" failed:\s*', "", core)
        why = re.sub(r"\s*\(line \d+, col \d+\)", "", why)
        return malformed(where, why)
    return SceneError(f"{where}: could not load the scene: {core}")


def _plugin_raised(text: str, where: str, path: Path) -> str | None:
    """A Python plugin's own exception (MaterialError, ValueError): its message, as the plugin wrote it."""
    if "Traceback (most recent call last)" not in text and "MaterialError" not in text:
        return None
    m = _PLUGIN_EXCEPTION.search(text)
    return f"{where}: {m.group(1).strip()}" if m else None


def _unreferenced(text: str, where: str, path: Path) -> str | None:
    unread = unread_parameters(text)
    if not unread:
        return None
    kind, plugin_type, names = unread
    names = names or ["?"]
    known = _plugin_parameters(plugin_type)
    hints = [difflib.get_close_matches(n, known, n=1) for n in names]
    guess = "".join(f" (did you mean {h[0]!r}?)" for h in hints if h) if len(names) == 1 else ""
    listed = (f"its parameters are {', '.join(repr(k) for k in known)}" if known else
              "see the Mitsuba plugin reference for its parameters")
    kind = "" if kind == "unknown" else f"{kind} "
    plural = "parameters" if len(names) > 1 else "parameter"
    return (f"{where}: the {kind}plugin {plugin_type!r} has no {plural} "
            f"{', '.join(repr(n) for n in names)}{guess}; fix the spelling or remove it "
            f"({listed}).")


def _not_found(text: str, where: str, path: Path) -> str | None:
    m = _NOT_FOUND.search(text)
    if not m:
        return None
    kind, plugin_type = m.group(1), m.group(2)
    guess = difflib.get_close_matches(plugin_type, _OWN_PLUGINS, n=1)
    hint = f" (did you mean {guess[0]!r}?)" if guess else ""
    return (f"{where}: there is no {kind} plugin named {plugin_type!r}{hint}; use a Mitsuba "
            f"built-in or one of phonglab's ({', '.join(_OWN_PLUGINS)}), registered by "
            f"phonglab.register() before loading from Python, or your own, registered by "
            f"'phonglab render --plugin FILE.py' (a file that calls "
            f"mi.register_{kind}({plugin_type!r}, ...)).")


def _unparsable_value(text: str, where: str, path: Path) -> str | None:
    m = _UNPARSABLE.search(text)
    if not m:
        return None
    kind, value = m.group(1), m.group(2)
    example = {"integer": "64", "boolean": "true"}.get(kind, "0.5")
    return (f"{where}: {value!r} is not a valid {kind} value; write one like "
            f"value=\"{example}\" (or pass a valid value for the scene parameter that gives it).")


def _missing_file(text: str, where: str, path: Path) -> str | None:
    m = _FILE_ERROR.search(text)
    if not m:
        return None
    plugin = _INSTANTIATE.search(text)
    needed = f" needed by the {plugin.group(1)} plugin {plugin.group(2)!r}" if plugin else ""
    return (f"{where}: cannot open the file {m.group(1)!r}{needed} ({m.group(2).strip()}); check "
            f"the path, which is relative to the scene file's folder {str(path.parent)!r}.")


def _out_of_range(text: str, where: str, path: Path) -> str | None:
    m = _OUT_OF_RANGE.search(text)
    if not m:
        return None
    plugin = _INSTANTIATE.search(text)
    owner = f" of the {plugin.group(1)} plugin {plugin.group(2)!r}" if plugin else ""
    return (f"{where}: {m.group(1)} = {m.group(2)}{owner} is outside its range "
            f"[{m.group(3)}, {m.group(4)}]; give a value in that range.")


def _unused_parameters(text: str, where: str, path: Path) -> str | None:
    if "Found unused parameters" not in text:
        return None
    given = re.findall(r"\$(\w+)=(\S*)", text)
    listed = ", ".join(f"{k}={v}" for k, v in given) or "?"
    return (f"{path}: the scene does not use the parameter(s) {listed} (it has no $name for "
            f"them); remove them, or add <default name=\"...\" value=\"...\"/> and use $name "
            f"in the file.")


def load_scene(path: str | Path, variant: str | None = None, **params) -> Any:
    """Load a Mitsuba XML scene with phonglab's plugins registered.

    Args:
        path: scene file, or the name of a shipped scene (``cornell_phong``).
        variant: Mitsuba variant to set first (default: the active one, else llvm_ad_rgb).
        **params: values for the scene's ``<default name=...>`` entries (spp, ...).

    Raises:
        SceneError: missing file, malformed XML, unknown parameter, unphysical material.
    """
    path = scene_path(path)
    registration.register(variant)
    try:
        return mi.load_file(str(path), **{k: v for k, v in params.items() if v is not None})
    except Exception as exc:  # Mitsuba raises RuntimeError with its own text
        if re.search(r"^KeyboardInterrupt\b", str(exc).strip(), re.M):
            # a Ctrl-C inside a Python plugin's constructor, turned into text by the loader
            raise KeyboardInterrupt from exc
        raise explain_load_error(path, exc) from exc


# --------------------------------------------------------------------------------------------
# Inspection (the XML alone)
# --------------------------------------------------------------------------------------------

#: BSDFs whose lobes are Dirac deltas (no histogram, no pdf).
DELTA_BSDFS = {"dielectric", "thindielectric", "conductor", "polarizer", "retarder"}


@dataclass
class SceneInfo:
    """What the scene file says about colour, spectra, delta BSDFs and its integrator."""

    path: Path
    defaults: dict[str, str]
    colored: list[str] = field(default_factory=list)      #: descriptions of non-gray values
    spectral: list[str] = field(default_factory=list)     #: descriptions of spectral data
    delta_bsdfs: list[str] = field(default_factory=list)  #: "dielectric 'glass'" ...
    integrator: str = "path"
    integrator_props: dict[str, str] = field(default_factory=dict)
    #: the scene's integrator as a ``mi.load_dict`` dictionary, or None with the reason in
    #: :attr:`integrator_dict_why` (a nested plugin, a reference, an unknown value type)
    integrator_dict: dict[str, Any] | None = None
    integrator_dict_why: str = ""
    gray_values: int = 0                                  #: gray colour values seen
    bsdf_types: set[str] = field(default_factory=set)     #: every <bsdf type=...> in the file
    #: the first top-level ``<sensor>``, ``$name``\ s substituted ("" when the file has none)
    sensor_xml: str = ""
    sampler: str = "independent"                          #: that sensor's sampler type

    @property
    def color(self) -> str:
        """'spectral', 'rgb' or 'mono': the leanest colour model the scene's data needs."""
        if self.spectral:
            return "spectral"
        if self.colored:
            return "rgb"
        return "mono"


def _substitute(root: ET.Element, values: dict[str, str], path: Path) -> None:
    """Replace ``$name`` in every attribute by its value, as Mitsuba's loader does."""
    pattern = re.compile(r"\$(\w+)")

    def repl(m: re.Match) -> str:
        if m.group(1) not in values:
            raise SceneError(f"{path}: '${m.group(1)}' is used but has no <default> and no "
                                f"value was given; add <default name=\"{m.group(1)}\" "
                                f"value=\"...\"/> to the scene or pass it as a parameter.")
        return values[m.group(1)]

    for el in root.iter():
        for key, value in el.attrib.items():
            if "$" in value:
                el.set(key, pattern.sub(repl, value))


def _floats(text: str) -> list[float]:
    return [float(t) for t in re.split(r"[,\s]+", text.strip()) if t]


def _is_gray(values: list[float]) -> bool:
    scale = max(abs(v) for v in values) or 1.0
    return max(values) - min(values) <= 1e-6 * scale


def _owner(parents: dict, el: ET.Element) -> str:
    """A short description of the plugin an element belongs to: "bsdf 'red' (lambert)"."""
    p = parents.get(el)
    while p is not None and p.tag not in ("bsdf", "emitter", "texture", "medium", "shape",
                                          "phase", "sensor"):
        p = parents.get(p)
    if p is None:
        return "the scene"
    ident = p.get("id")
    return f"{p.tag} {ident!r} ({p.get('type')})" if ident else f"{p.tag} ({p.get('type')})"


def _bitmap_is_gray(filename: Path) -> bool | None:
    """True/False when the image file's channels are (not) all equal; None when unreadable."""
    try:
        if mi.variant() is None:
            registration.register()
        arr = np.array(mi.Bitmap(str(filename)), dtype=np.float64)
    except Exception:
        return None
    if arr.ndim < 3 or arr.shape[2] == 1:
        return True
    rgb = arr[..., :3]
    return bool(np.all(np.abs(rgb - rgb[..., :1]) <= 1e-6 * max(1.0, float(np.abs(rgb).max()))))


def inspect_scene(scene: str | Path, **params) -> SceneInfo:
    """Read a scene file's colours, spectral data, delta BSDFs and integrator (no rendering).

    ``params`` override the scene's ``<default>`` values, as in :func:`load_scene`.
    ``<include>``\\ d files are inspected too.  Unused definitions count (a coloured BSDF that
    nothing references still makes the scene ``rgb``): the inspection errs towards more colour.
    """
    path = scene_path(scene)
    root = parse_xml(path)
    defaults = {d.get("name"): d.get("value") for d in root.iter("default") if d.get("name")}
    values = dict(defaults)
    values.update({k: str(v) for k, v in params.items() if v is not None})
    _substitute(root, values, path)
    info = SceneInfo(path=path, defaults=defaults)
    _scan(root, path, info, values)
    integ = root.find("integrator")
    if integ is not None:
        info.integrator = integ.get("type", "path")
        info.integrator_props = {c.get("name"): c.get("value") for c in integ
                                 if c.get("name") and c.get("value") is not None}
    info.integrator_dict, info.integrator_dict_why = _integrator_dict(integ)
    sensor = root.find("sensor")
    if sensor is not None:
        info.sensor_xml = ET.tostring(sensor, encoding="unicode")
        sampler = sensor.find("sampler")
        info.sampler = sampler.get("type", "independent") if sampler is not None else "independent"
    return info


def sensor_with_sampler(info: SceneInfo, sampler: str, version: str = "3.0.0"):
    """The scene's first sensor rebuilt with a sampler of type ``sampler`` (same camera, film
    and sample count), for ``mi.render(scene, sensor=...)`` in the active variant.

    Raises:
        SceneError: the file has no top-level ``<sensor>``, or that sensor cannot be built on
            its own (it refers to objects defined elsewhere in the scene, say).
    """
    if not info.sensor_xml:
        raise SceneError(f"{info.path}: no top-level <sensor> to rebuild with the {sampler!r} "
                         f"sampler; render it with its own sampler.")
    el = ET.fromstring(info.sensor_xml)
    node = el.find("sampler")
    if node is None:
        node = ET.SubElement(el, "sampler")
    node.set("type", sampler)
    el.set("version", version)
    try:
        with quiet_mitsuba():  # mono variants: "film output set to luminance", as load_scene
            return mi.load_string(ET.tostring(el, encoding="unicode"))
    except Exception as exc:  # Mitsuba's loader: a reference, a property the sampler refuses
        why = str(exc).strip().splitlines()[-1] if str(exc).strip() else type(exc).__name__
        raise SceneError(f"{info.path}: its sensor cannot be rebuilt with the {sampler!r} "
                         f"sampler ({why}); render it with its own sampler.") from exc


_VALUE_TYPES = {"integer": int, "float": float, "string": str,
                "boolean": lambda v: v.strip().lower() == "true"}


def _integrator_dict(integ: ET.Element | None) -> tuple[dict[str, Any] | None, str]:
    """The ``<integrator>`` element as a ``mi.load_dict`` dictionary, or (None, why not)."""
    if integ is None:
        return {"type": "path"}, ""          # Mitsuba's default integrator
    d: dict[str, Any] = {"type": integ.get("type", "path")}
    for c in integ:
        name, value = c.get("name"), c.get("value")
        try:
            plain = _plain(c)
        except ValueError:
            return None, f"its <{c.tag} name={name!r}> has the value {value!r}"
        if plain is not None:
            d[name] = plain
        elif c.tag == "rgb" and name and value is not None:
            d[name] = {"type": "rgb", "value": _floats(value)}
        else:
            return None, f"it holds a <{c.tag}> element that phonglab does not rebuild"
    return d, ""


def plugin_element(path: str | Path, tag: str, ident: str | None = None) -> ET.Element | None:
    """The ``<tag>`` element of an XML file: its root (``ident`` None) or the one with
    ``id="ident"`` anywhere in it (a scene's material), ``$name``\\ s substituted from the
    file's ``<default>`` entries; None when there is no such element (or a ``$name`` has no
    default).  ``<include>``\\ d files are not searched."""
    path = Path(path)
    root = parse_xml(path)
    values = {d.get("name"): d.get("value") for d in root.iter("default") if d.get("name")}
    try:
        _substitute(root, values, path)
    except SceneError:
        return None
    if ident is None:
        return root if root.tag == tag else None
    return next((el for el in root.iter(tag) if el.get("id") == ident), None)


def element_parameters(el: ET.Element) -> dict[str, Any]:
    """The plain parameters an element gives its plugin: each ``<float>``, ``<integer>``,
    ``<boolean>`` and ``<string>`` child as its value (a value that does not parse, a nested
    plugin, a colour or a reference is left out)."""
    out: dict[str, Any] = {}
    for c in el:
        try:
            plain = _plain(c)
        except ValueError:
            continue
        if plain is not None:
            out[c.get("name")] = plain
    return out


def _plain(c: ET.Element) -> Any:
    """The value of a named ``<float>``/``<integer>``/``<boolean>``/``<string>`` element, None
    for any other element; ValueError when its value does not parse."""
    name, value = c.get("name"), c.get("value")
    if c.tag in _VALUE_TYPES and name and value is not None:
        return _VALUE_TYPES[c.tag](value)
    return None


def integrator_with_depth(info: SceneInfo, max_depth: int):
    """The scene's own integrator with ``max_depth`` set (what ``--max-depth`` means).

    Raises:
        SceneError: the integrator has no ``max_depth`` parameter, or the scene's integrator
            cannot be rebuilt outside its file.
    """
    if info.integrator_dict is None:
        raise SceneError(
            f"{info.path}: cannot apply a max_depth to its {info.integrator!r} integrator "
            f"({info.integrator_dict_why}); add <default name=\"max_depth\" value=\"8\"/> and "
            f"max_depth=\"$max_depth\" to the integrator, or render without --max-depth.")
    d = dict(info.integrator_dict, max_depth=int(max_depth))
    try:
        return mi.load_dict(d)
    except Exception as exc:  # Mitsuba: unreferenced property, or the plugin's own check
        raise SceneError(
            f"{info.path}: the scene's {info.integrator!r} integrator does not take "
            f"max_depth={max_depth} ({str(exc).strip().splitlines()[-1]}); render without "
            f"--max-depth.") from exc


def _scan(root: ET.Element, path: Path, info: SceneInfo, values: dict[str, str]) -> None:
    parents = {c: p for p in root.iter() for c in p}
    for el in root.iter():
        where = _owner(parents, el)
        name = el.get("name", "")
        if el.tag == "include" and el.get("filename"):
            sub = (path.parent / el.get("filename")).resolve()
            sub_root = parse_xml(sub)
            _substitute(sub_root, values, sub)
            _scan(sub_root, sub, info, values)
        elif el.tag == "rgb":
            try:
                vals = _floats(el.get("value", ""))
            except ValueError:
                raise SceneError(f"{path}: <rgb name={name!r}> of {where} has value "
                                    f"{el.get('value')!r}; write three numbers like "
                                    f"\"0.5, 0.5, 0.5\".") from None
            if vals and not _is_gray(vals):
                info.colored.append(f"{where} {name} = ({el.get('value')})")
            else:
                info.gray_values += 1
        elif el.tag == "spectrum":
            kind, value = el.get("type"), el.get("value")
            if el.get("filename"):
                info.spectral.append(f"{where} {name} reads spectral file {el.get('filename')}")
            elif kind and kind not in ("uniform",):
                info.spectral.append(f"{where} {name} is a '{kind}' spectrum")
            elif value is not None and ":" in value:
                info.spectral.append(f"{where} {name} lists wavelengths ({value[:40]})")
            else:
                info.gray_values += 1
        elif el.tag == "texture" and el.get("type") == "bitmap":
            for c in el:
                if c.get("name") == "filename":
                    gray = _bitmap_is_gray(path.parent / c.get("value", ""))
                    if not gray:
                        info.colored.append(f"{where} bitmap {c.get('value')} "
                                            f"({'not gray' if gray is False else 'unreadable'})")
                    else:
                        info.gray_values += 1
        elif el.tag == "emitter" and el.get("type") in ("envmap",):
            for c in el:
                if c.get("name") == "filename":
                    gray = _bitmap_is_gray(path.parent / c.get("value", ""))
                    if not gray:
                        info.colored.append(f"{where} environment map {c.get('value')}")
        elif el.tag == "emitter" and el.get("type") in ("sunsky", "sky", "sun"):
            info.colored.append(f"{where}: a sky model is coloured")
        if el.tag == "bsdf":
            kind = el.get("type")
            info.bsdf_types.add(kind)
            if kind == "conductor":
                material = next((c.get("value") for c in el if c.get("name") == "material"),
                                "none")
                if material != "none":
                    info.spectral.append(f"{where} uses measured spectral IOR data "
                                         f"(material {material!r})")
            if kind in DELTA_BSDFS:
                ident = el.get("id")
                info.delta_bsdfs.append(f"{kind} {ident!r}" if ident else kind)


def path_integrator(max_depth: int, info: SceneInfo):
    """A ``path`` integrator of depth ``max_depth`` that keeps the scene's rr_depth and hide_emitters."""
    d: dict[str, Any] = {"type": "path", "max_depth": int(max_depth)}
    for key, cast in (("rr_depth", int), ("hide_emitters", lambda s: s.lower() == "true")):
        if key in info.integrator_props:
            d[key] = cast(info.integrator_props[key])
    return mi.load_dict(d)
