"""The validator's user input checked without Mitsuba: the topics, and the error class.

``--set NAME=VALUE`` values are parsed by :func:`phonglab.settings.parse_sets` (the grammar is
documented there); plugins are loaded by :func:`phonglab.settings.load_plugin`.
"""

from __future__ import annotations

from ..errors import PhonglabError
from .bsdf.topics import TOPICS


class ValidateError(PhonglabError):
    """A BSDF, plugin file, parameter or topic the validator cannot use."""


def check_topics(topics, table=TOPICS) -> tuple[str, ...]:
    """The topics to run, in ``table`` order (all of ``table`` when ``topics`` is empty)."""
    topics = tuple(topics or table)
    bad = [t for t in topics if t not in table]
    if bad:
        raise ValidateError(f"unknown topic {bad[0]!r}; choose from {', '.join(table)}")
    return tuple(t for t in table if t in topics)


def xml_head(path: str) -> str:
    """The first 200 characters of an XML file after its declaration ("" when unreadable):
    enough to see which element (``<bsdf``, ``<emitter``, ``<integrator``) it holds."""
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            text = f.read(4096)
    except OSError:
        return ""
    return text.split("?>", 1)[-1].lstrip()[:200]
