"""Command-line options several subcommands share."""

from __future__ import annotations

import argparse

from ..settings import split


def scene_param(text: str) -> tuple[str, str]:
    """``NAME=VALUE`` → (name, value): one of the scene's ``<default>`` parameters.

    The value stays text (:mod:`phonglab.settings`): Mitsuba substitutes it into the XML.
    """
    pair = split(text)
    if pair is None:
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE (a scene <default>, e.g. "
                                         f"res=256), got {text!r}")
    return pair


def add_scene_params(p: argparse.ArgumentParser, *flags: str) -> None:
    """``-D NAME=VALUE`` (repeatable, into ``args.params``): a value for one of the scene's
    ``<default name=...>`` entries, as Mitsuba's own ``mitsuba -D`` sets them."""
    p.add_argument(*(flags or ("-D", "--set")), dest="params", type=scene_param,
                   action="append", default=[], metavar="NAME=VALUE",
                   help="a value for one of the scene's <default> parameters, e.g. -D res=256 "
                        "(repeatable)")
