"""The parser the command reference documents (``commands/*.md``, sphinx-argparse).

It is :func:`phonglab.cli.build_parser`'s, with one change for the page: every parser's epilog
is preformatted text (``RawDescriptionHelpFormatter``: the example lines), which
sphinx-argparse would parse as reST and join into one paragraph; here it becomes a literal
block (plain text), shown as ``--help`` shows it.
"""

from __future__ import annotations

import argparse
import textwrap

from phonglab.cli import build_parser


def parser() -> argparse.ArgumentParser:
    top = build_parser()
    subparsers = next(a for a in top._actions if isinstance(a, argparse._SubParsersAction))
    for p in (top, *subparsers.choices.values()):
        if p.epilog:
            p.epilog = ".. code-block:: text\n\n" + textwrap.indent(p.epilog.rstrip(), "   ")
    return top
