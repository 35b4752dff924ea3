"""The validator's user input, checked without Mitsuba: topics, ``--set`` values, the error class.

``--set NAME=VALUE`` -> the parameters of a ``mi.load_dict`` dictionary.

Values: ``true``/``false`` -> bool; an integer literal -> int; a number -> float; three numbers
separated by commas -> ``{"type": "rgb", "value": [r, g, b]}``; anything else -> str (e.g.
``distribution=ggx``, a filename).  A dotted name sets a nested object:
``--set nested.type=diffuse --set nested.reflectance=0.3`` gives
``{"nested": {"type": "diffuse", "reflectance": 0.3}}`` (``twosided``, ``mask``, ``bumpmap``,
...); a texture parameter is set the same way (``--set reflectance.type=checkerboard``).
"""

from __future__ import annotations

import math
import re

from ..errors import PhonglabError
from .topics import TOPICS

_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*$")


class ValidateError(PhonglabError):
    """A BSDF, plugin file, parameter or topic the validator cannot use."""


class ParameterError(ValidateError, ValueError):
    """A ``--set`` argument that is not NAME=VALUE with a usable value."""


def check_topics(topics) -> tuple[str, ...]:
    """The topics to run, in table order (all when ``topics`` is empty)."""
    topics = tuple(topics or TOPICS)
    bad = [t for t in topics if t not in TOPICS]
    if bad:
        raise ValidateError(f"unknown topic {bad[0]!r}; choose from {', '.join(TOPICS)}")
    return tuple(t for t in TOPICS if t in topics)


def parse_value(text: str):
    t = text.strip()
    if t.lower() in ("true", "false"):
        return t.lower() == "true"
    parts = t.split(",")
    if len(parts) == 3:
        try:
            rgb = [float(p) for p in parts]
        except ValueError:
            return t
        if not all(math.isfinite(x) for x in rgb):
            raise ParameterError(f"the colour {text!r} has a non-finite component; give three "
                                 f"finite numbers like 0.2,0.3,0.4")
        return {"type": "rgb", "value": rgb}
    if re.fullmatch(r"[+-]?\d+", t):
        return int(t)
    try:
        x = float(t)
    except ValueError:
        return t
    if not math.isfinite(x):
        raise ParameterError(f"the value {text!r} is not finite; give a finite number")
    return x


def parse_sets(items) -> dict:
    """NAME=VALUE strings -> a (nested) parameter dict; :class:`ParameterError` on bad input."""
    out: dict = {}
    for item in items or ():
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep or not _NAME.match(name) or value.strip() == "":
            raise ParameterError(f"--set {item!r} is not NAME=VALUE; write e.g. --set alpha=0.2 "
                                 f"or --set reflectance=0.2,0.3,0.4")
        *path, leaf = name.split(".")
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
        node[leaf] = parse_value(value)
    return out
