"""Sphinx configuration of the phonglab docs site (``make docs``; ``tests/test_docs.py``).

Sources stay where they are: this folder's Markdown (MyST), the notebooks (``docs/notebooks``
is a symlink to ``../notebooks``; myst-nb shows what they store, never executes them: the
tests do), ``BENCHMARKS.md`` (included by ``benchmarks.md``), the command reference from the
argparse parsers (sphinx-argparse, :mod:`_cli`) and the API reference from the module
docstrings (autodoc).  Built with ``-W``: every warning is an error.
"""

from __future__ import annotations

import importlib.util
import os
import re
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
# This checkout's source, whatever phonglab the environment has installed; _cli beside us.
sys.path[:0] = [str(ROOT / "src"), str(DOCS)]

# phonglab.plugins is the repository's plugins/ folder (pyproject's package-dir): bound to this
# checkout's folder too, so that the API pages show these plugins, not an installed copy.
_spec = importlib.util.spec_from_file_location(
    "phonglab.plugins", ROOT / "plugins" / "__init__.py",
    submodule_search_locations=[str(ROOT / "plugins")])
sys.modules["phonglab.plugins"] = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(sys.modules["phonglab.plugins"])

# The plugin classes derive from mi.BSDF / mi.SamplingIntegrator, which exist once a variant is
# set; scalar_rgb needs no LLVM.
import mitsuba  # noqa: E402

mitsuba.set_variant("scalar_rgb")

project = "phonglab"
author = "phonglab developers"
copyright = "phonglab developers"

extensions = [
    "myst_nb",                  # Markdown (MyST) and notebooks
    "sphinx.ext.autodoc",       # the API reference, from the docstrings (reST, no napoleon)
    "sphinx.ext.mathjax",
    "sphinxarg.ext",            # the command reference, from the argparse parsers
]
html_theme = "furo"
html_title = "phonglab"
# bench/ and img/ hold data and figures the pages show, not pages.
exclude_patterns = ["**/.ipynb_checkpoints", "bench", "img"]

nb_execution_mode = "off"       # the notebooks as stored (tests/test_notebooks.py runs them)
myst_enable_extensions = ["dollarmath", "amsmath"]
myst_heading_anchors = 4        # the docs link their own sections by GitHub's anchors

# Only phonglab's own words: a plugin method without a docstring of its own does not show
# Mitsuba's C++ documentation of the method it overrides.
autodoc_inherit_docstrings = False
autodoc_member_order = "bysource"
smartquotes = False             # "--set" stays two hyphens in the command reference

# The plugins' parameter tables use Mitsuba's substitutions (|float|, |spectrum|, ...), as
# Mitsuba's own plugin docs do; rst_prolog does not reach docstrings read from a MyST page, so
# they are replaced where autodoc reads them.
_MITSUBA_TYPES = re.compile(r"\|(float|spectrum|texture|bool|int|string)\|")


def _mitsuba_types(app, what, name, obj, options, lines: list[str]) -> None:
    lines[:] = [_MITSUBA_TYPES.sub(r"*\1*", line) for line in lines]


# --- links written for the repository, read in the site ----------------------------------
# The Markdown links files by their place in the repository, which is right on GitHub and in
# an editor; in the site three kinds of target live elsewhere or nowhere, and are mapped here
# as each page is read (the files are not changed):
#   * the notebooks (``../notebooks/x.ipynb``) are pages under docs/notebooks/, a symlink,
#     which Sphinx resolves when it follows a path: they are linked by their page name;
#   * BENCHMARKS.md is the page benchmarks.md;
#   * a folder (``../notebooks``, ``docs/bench/``) has no page: its link text is kept.
# Links to other files (a plugin's source line) stay, and Sphinx copies the file.
_LINK = re.compile(r"(?<!!)\[([^\]\n]*)\]\(([^()\s#]+)(#[^()\s]*)?\)")


def _site_links(text: str, written_in: Path, read_from: Path) -> str:
    """``text`` with its links to the repository's files mapped to the site: a link is written
    relative to ``written_in`` and MyST resolves it relative to ``read_from``."""

    def site(m: re.Match) -> str:
        label, target, anchor = m.group(1), m.group(2), m.group(3) or ""
        if ":" in target:                                   # a URL
            return m.group(0)
        path = (written_in / target).resolve()
        if not path.exists() or not path.is_relative_to(ROOT):
            return m.group(0)                               # MyST reports it
        if path.is_dir():
            return label
        if path == ROOT / "BENCHMARKS.md":
            path = DOCS / "benchmarks.md"
        elif path.is_relative_to(ROOT / "notebooks") and path.suffix == ".ipynb":
            page = (Path("notebooks") / path.relative_to(ROOT / "notebooks")).with_suffix("")
            return f"{{doc}}`{label.replace('`', '')} </{page.as_posix()}>`"
        return f"[{label}]({os.path.relpath(path, read_from)}{anchor})"

    return _LINK.sub(site, text)


def _source_read(app, docname: str, source: list[str]) -> None:
    # MyST resolves a notebook's links against its real folder (notebooks/, not the symlink).
    where = Path(app.env.doc2path(docname)).resolve().parent
    source[0] = _site_links(source[0], where, where)


def _include_read(app, path, docname, content: list[str]) -> None:
    # An included file's links are resolved against the including page's folder.
    # (MyST's include: ``path`` relative to the source folder, ``docname`` the page's stem.)
    content[0] = _site_links(content[0], (Path(app.srcdir) / path).resolve().parent, DOCS)


def setup(app):
    app.connect("source-read", _source_read)
    app.connect("include-read", _include_read)
    app.connect("autodoc-process-docstring", _mitsuba_types)
