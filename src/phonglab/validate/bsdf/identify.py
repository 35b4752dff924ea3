r"""Which Mitsuba built-in BSDF a loaded object is, and the built-in BSDFs inside it.

A documented finding follows the plugin that is loaded, not the way it was named
(:mod:`phonglab.validate.builtin`): :func:`identify` reads the built-in from the object itself
and its parameters from everything that describes it.

* Which built-in: a C++ plugin's Python type is ``mi.BSDF`` itself (a Python plugin's is its own
  class, phonglab's ``lambert`` and ``phong`` included), and its ``class_name()`` names its C++
  class, which :data:`CLASSES` maps to the plugin type (``RoughConductor`` ->
  ``roughconductor``; the map is held against every case of the conformance table by
  tests/test_validate_builtin_identity.py).
* Its parameters: the load-time ones the spec gives (a type name's or dict's parameters; an
  XML file's, or a scene element's found by its ``id``, ``<float>``/``<integer>``/
  ``<boolean>``/``<string>`` children, ``$name`` defaults substituted), then the settings the
  object prints (``to_string()``: ``distribution = ggx``, which is what it really loaded),
  then the ones derived from what it traverses (:data:`DERIVED`).  The traversed values
  themselves are added by the runner (:func:`phonglab.validate.core.parameter_values`).

:func:`children` finds the BSDFs a plugin holds: what its ``traverse()`` hands the callback
(``callback.put("nested", self.nested, ...)``: Mitsuba's ``twosided`` puts ``brdf_0`` and
``brdf_1``, ``blendbsdf`` ``bsdf_0``/``bsdf_1``) and, for a Python plugin, its attributes that
hold an ``mi.BSDF`` (or a list of them), each under the name it is known by there; then
theirs, with dotted paths (``nested.brdf_0``).
"""

from __future__ import annotations

import re

import mitsuba as mi

#: C++ class name (``class_name()``) -> plugin type, for Mitsuba 3.9.1's BSDFs
#: (src/bsdfs/*.cpp).
CLASSES = {
    "SmoothDiffuse": "diffuse", "SmoothPlastic": "plastic", "RoughPlastic": "roughplastic",
    "SmoothConductor": "conductor", "RoughConductor": "roughconductor",
    "SmoothDielectric": "dielectric", "ThinDielectric": "thindielectric",
    "RoughDielectric": "roughdielectric", "Principled": "principled",
    "PrincipledThin": "principledthin", "TwoSidedBRDF": "twosided", "BlendBSDF": "blendbsdf",
    "MaskBSDF": "mask", "Hair": "hair", "Null": "null", "BumpMap": "bumpmap",
    "NormalMap": "normalmap", "LinearPolarizer": "polarizer", "LinearRetarder": "retarder",
    "CircularPolarizer": "circular", "PolarizedPlastic": "pplastic",
    "Measured": "measured", "MeasuredPolarized": "measured_polarized",
}

#: Mitsuba's default exterior IOR (air, 1.000277; the plugins' ``ext_ior`` default).
AIR = 1.000277
#: Plugins that traverse ``eta`` = int_ior / ext_ior and document findings at ``int_ior``: an
#: object that was not given ``int_ior`` (a child, a scene material with a named IOR) has
#: ``int_ior`` = eta × air, the interior IOR that gives the same eta against the default
#: exterior (what the findings' causes depend on).
DERIVED = ("plastic", "roughplastic", "pplastic")

#: A top-level setting of ``to_string()``: ``  distribution = beckmann,``.
_SETTING = re.compile(r"^  (\w+) = ([A-Za-z_]\w*),?$", re.M)


def builtin_type(plugin) -> str | None:
    """The plugin type of a Mitsuba built-in BSDF object, None for a Python plugin or a class
    :data:`CLASSES` does not name."""
    if type(plugin) is not mi.BSDF:
        return None
    try:
        return CLASSES.get(plugin.class_name())
    except Exception:
        return None


def identify(plugin, spec=None, origin=None) -> tuple[str, dict] | None:
    """(plugin type, load-time parameters) of the built-in BSDF ``plugin`` (module docstring),
    None when it is not one.  ``spec``: what it was loaded from (a dict with ``type``, or
    ``{"file": xml}``); ``origin``: where a loaded object came from (``{"file": scene, "id":
    ID}``)."""
    name = builtin_type(plugin)
    if name is None:
        return None
    params: dict = {}
    source = spec if spec else origin
    if isinstance(source, dict) and "file" in source:
        params = _xml_parameters(source["file"], source.get("id"), name)
    elif isinstance(source, dict) and source.get("type") == name:
        params = {k: v for k, v in source.items()
                  if k != "type" and isinstance(v, (int, float, str, bool))}
    params.update(settings(plugin))
    if name in DERIVED and "int_ior" not in params:
        eta = _eta(plugin)
        if eta is not None:
            params["int_ior"] = eta * AIR
    return name, params


def settings(plugin) -> dict[str, str]:
    """The word-valued top-level settings ``to_string()`` prints (``distribution``)."""
    try:
        text = str(plugin)
    except Exception:
        return {}
    return {k: v for k, v in _SETTING.findall(text) if k == "distribution"}


def _xml_parameters(path, ident, name: str) -> dict:
    from ...engine.scenes import element_parameters, plugin_element
    from ...errors import SceneError
    try:
        el = plugin_element(path, "bsdf", ident)
    except (SceneError, OSError):
        return {}
    if el is None or el.get("type") != name:
        return {}
    return element_parameters(el)


def _eta(plugin) -> float | None:
    from .ranges import traversed
    try:
        return traversed(plugin).get("eta")
    except Exception:
        return None


_COLLECT: dict = {}


def _collector():
    """A traversal callback that keeps the BSDFs a plugin puts, by name (its class is made per
    variant: ``mi.TraversalCallback`` exists only once a variant is set)."""
    variant = mi.variant()
    if variant not in _COLLECT:
        class Collect(mi.TraversalCallback):
            def __init__(self):
                super().__init__()
                self.objects: list[tuple[str, object]] = []

            def put(self, name, value, flags=None):
                if isinstance(value, mi.BSDF):
                    self.objects.append((str(name), value))

        _COLLECT[variant] = Collect
    return _COLLECT[variant]()


def children(plugin, _prefix: str = "", _seen=None) -> list[tuple[str, object]]:
    """(path, BSDF) of every BSDF ``plugin`` holds, depth first (module docstring); each
    object once, under the first name it is found by."""
    seen = _seen if _seen is not None else [plugin]
    found: list[tuple[str, object]] = []
    cb = _collector()
    try:
        plugin.traverse(cb)
    except Exception:
        pass
    found += cb.objects
    if type(plugin) is not mi.BSDF:          # a Python plugin: its attributes too
        for attr, value in sorted(getattr(plugin, "__dict__", {}).items()):
            values = value if isinstance(value, (list, tuple)) else [value]
            found += [(attr if len(values) == 1 else f"{attr}[{i}]", v)
                      for i, v in enumerate(values) if isinstance(v, mi.BSDF)]
    out = []
    for name, obj in found:
        if any(obj is s for s in seen):
            continue
        seen.append(obj)
        path = f"{_prefix}{name}"
        out.append((path, obj))
        out += children(obj, path + ".", seen)
    return out
