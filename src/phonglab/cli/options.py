"""Command-line options several subcommands share."""

from __future__ import annotations

import argparse

from ..errors import PhonglabError
from ..settings import SEED_MAX, ParameterError, check_seed, split


def seed(text: str) -> int:
    """``--seed`` as an int in [0, :data:`phonglab.settings.SEED_MAX`], else one sentence."""
    try:
        return check_seed(int(text))
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc) if isinstance(exc, ParameterError) else
                                         f"the seed must be a whole number, got {text!r}") from None


def add_seed(p: argparse.ArgumentParser) -> None:
    """``--seed S`` (default 0), checked by :func:`seed` before any work."""
    p.add_argument("--seed", type=seed, default=0, metavar="S",
                   help=f"random seed, 0 to {SEED_MAX} (default 0)")


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


def add_plugin(p: argparse.ArgumentParser, register: str) -> None:
    """``--plugin FILE.py`` (repeatable): a Python file run once after the variant is set, as
    ``phonglab validate --plugin`` runs it (:func:`phonglab.validate.loading.load_plugins`);
    ``register``: the call such a file makes, for the help."""
    p.add_argument("--plugin", action="append", default=[], metavar="FILE.py",
                   help=f"a Python file run once after the variant is set; it calls {register} "
                        f"with a name of its own (repeatable)")


def check_plugin_files(paths, register: str) -> None:
    """Each ``--plugin`` path is a file, before any work (one sentence otherwise, naming the
    call ``register`` such a file makes: :func:`phonglab.validate.inputs.check_plugin_file`)."""
    from ..validate.inputs import check_plugin_file

    for path in paths:
        check_plugin_file(path, register)


def load_plugin_files(paths) -> list[tuple[str, str]]:
    """Run the ``--plugin`` files once in the active variant (names Mitsuba or phonglab already
    has refused): :func:`phonglab.validate.loading.load_plugins`."""
    if not paths:
        return []
    from ..validate.loading import load_plugins

    return load_plugins(paths)


def add_timeout(p: argparse.ArgumentParser, what: str) -> None:
    """``--timeout SECONDS``: the limit of each ``what`` (and of loading each ``--plugin``
    file), checked by :func:`check_timeout` before any work
    (:func:`phonglab.validate.timeout.topic_timeout`)."""
    p.add_argument("--timeout", type=float, default=None, metavar="SECONDS",
                   help=f"stop a {what} that runs longer than this (and a --plugin file that "
                        f"takes longer to load): {what} becomes a failing row, a file one "
                        f"sentence. Stops Python code (a plugin's eval that loops forever), not "
                        f"a compiled Dr.Jit kernel")


def check_timeout(seconds: float | None) -> None:
    """``--timeout`` is a finite number of seconds > 0 (or not given), else one sentence."""
    if seconds is not None and not 0 < seconds < float("inf"):
        raise PhonglabError(f"--timeout must be a number of seconds > 0, got {seconds:g}")
