"""The validator's user input checked without Mitsuba: the topics, and the error class.

``--set NAME=VALUE`` values are parsed by :func:`phonglab.settings.parse_sets` (the grammar is
documented there); plugins are loaded by :func:`phonglab.settings.load_plugin`.
"""

from __future__ import annotations

from pathlib import Path

from .kind import ValidateError, check_topics

__all__ = ["ValidateError", "check_plugin_file", "check_topics", "xml_head", "xml_root_tag"]

#: What a ``--plugin`` file calls when the kind it registers is not known yet.
ANY_REGISTER = "one of Mitsuba's mi.register_* functions"


def check_plugin_file(path, register: str = ANY_REGISTER) -> Path:
    """A ``--plugin`` file that exists and is not a folder, else one sentence naming which and
    the call (``register``) such a file makes."""
    p = Path(path)
    if not p.is_file():
        raise ValidateError(f"plugin file {str(path)!r} "
                            f"{'is a folder' if p.is_dir() else 'does not exist'}; give the path "
                            f"of a Python file that calls {register}")
    return p


def xml_head(path: str) -> str:
    """The first 200 characters of an XML file after its declaration ("" when unreadable):
    enough to see which element (``<bsdf``, ``<emitter``, ``<integrator``) it holds."""
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            text = f.read(4096)
    except OSError:
        return ""
    return text.split("?>", 1)[-1].lstrip()[:200]


def xml_root_tag(path: str) -> str:
    """The name of an XML file's first element (``bsdf``, ``scene``; "" when there is none),
    comments skipped."""
    head = xml_head(path)
    while head.startswith("<!--"):
        head = head.split("-->", 1)[-1].lstrip()
    if not head.startswith("<"):
        return ""
    name = head[1:].split(None, 1)[0] if head[1:].split() else ""
    return name.rstrip(">/").strip()
