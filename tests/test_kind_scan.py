"""A kind is one complete record: no module that validates *any* kind names one.

A plugin kind is its folder of ``phonglab.validate`` (whose ``__init__`` declares its
:class:`~phonglab.validate.kind.Kind`) and one line of ``validate/registry.py``.  Everything
else that validates plugins -- the kind-independent modules of ``phonglab.validate``, the
command line's ``validate`` and shared options, ``phonglab.testing``, ``dispatch``,
``registration``, ``parallel``, the conformance script, the Makefile and the packaging -- reads
the kinds from :data:`~phonglab.validate.registry.KINDS`.  This test scans them for a kind's
name, word (and its plural), Mitsuba class, ``ObjectType`` member, XML tag or registration call:

* in Python code: every identifier (split at ``_`` and at case changes: ``scene_bsdf``,
  ``SamplingIntegrator``) and every string literal, f-strings included; docstrings and comments
  are prose (an example, a source to cite) and are not scanned;
* in the Makefile and pyproject.toml: every line, its comment cut off.

A mention that means something else than the kind is listed in :data:`EXCEPTIONS` with why.
The scanner itself is tested on planted mentions of two made-up kinds
(:func:`test_the_scanner_catches_a_planted_mention`), so a scan that finds nothing is a scan
that works.
"""

from __future__ import annotations

import ast
import io
import re
import tokenize
from dataclasses import dataclass
from pathlib import Path

import pytest

from phonglab.validate.kind import Kind
from phonglab.validate.registry import KINDS

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src" / "phonglab"

#: The files that validate any kind (the registry and the kind folders are the kinds' own).
SCANNED = sorted(
    [p for p in (SRC / "validate").glob("*.py") if p.name != "registry.py"]
    + [SRC / "cli" / "validate.py", SRC / "cli" / "options.py", SRC / "testing.py",
       SRC / "dispatch.py", SRC / "registration.py", *(SRC / "parallel").glob("*.py"),
       ROOT / "scripts" / "conformance.py", ROOT / "setup.py", ROOT / "Makefile",
       ROOT / "pyproject.toml"])

#: (file relative to the checkout, a text of the line a mention lies on) -> why it is not a
#: kind's.
EXCEPTIONS = {
    ("src/phonglab/registration.py", '("lambert", "lambert", "bsdf")'):
        "phonglab's own BSDF plugins, registered with the call of the kind they are",
    ("src/phonglab/registration.py", '("phong", "phong", "bsdf")'):
        "phonglab's own BSDF plugins, registered with the call of the kind they are",
    ("src/phonglab/registration.py", '("whitted", "whitted", "integrator")'):
        "phonglab's own integrator plugin, registered with the call of its kind",
    ("pyproject.toml", 'description = "Lambert and modified-Phong BSDFs for Mitsuba 3'):
        "the package's description: phonglab's own BSDF plugins",
}


@dataclass(frozen=True)
class Mention:
    path: str          #: relative to the checkout
    line: int
    kind: str          #: the kind named
    text: str          #: the identifier, string literal or line it lies in
    source: str        #: the whole line

    def __str__(self) -> str:
        return f"{self.path}:{self.line}: the {self.kind} kind in {self.text!r}"


def forms(kind) -> set[str]:
    """Every way a kind is named (lower case): its name, word and plural, Mitsuba class,
    ObjectType member, XML tag and registration call (with and without ``mi.``)."""
    out = {kind.name, kind.word, kind.plural, kind.word + "s", kind.class_name,
           kind.object_type, kind.tag, kind.register, kind.register.removeprefix("mi.")}
    return {f.lower() for f in out if f}


def _words(identifier: str) -> list[str]:
    """``scene_bsdf`` -> [scene, bsdf]; ``SamplingIntegrator`` -> [sampling, integrator]."""
    parts = []
    for piece in identifier.split("_"):
        parts += re.findall(r"[A-Z]+(?![a-z])|[A-Z]?[a-z0-9]+", piece) or [piece]
    return [p.lower() for p in parts if p]


def _in_text(text: str, kinds) -> list[str]:
    """The kinds a piece of text names (a form between non-letters, case ignored)."""
    low = text.lower()
    return [k.name for k in kinds
            if any(re.search(rf"(?<![a-z0-9]){re.escape(f)}(?![a-z0-9])", low)
                   for f in forms(k))]


def _in_identifier(name: str, kinds) -> list[str]:
    words = _words(name)
    joined = " ".join(words)
    out = []
    for k in kinds:
        for f in forms(k):
            fw = " ".join(_words(f.replace(" ", "_")))
            if fw and re.search(rf"(?<![a-z0-9]){re.escape(fw)}(?![a-z0-9])", joined):
                out.append(k.name)
                break
    return out


def _prose_lines(source: str) -> set[int]:
    """The lines of docstrings and other bare string statements."""
    lines = set()
    for node in ast.walk(ast.parse(source)):
        if (isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant)
                and isinstance(node.value.value, str)):
            lines.update(range(node.lineno, node.end_lineno + 1))
    return lines


def scan_python(source: str, path: str = "<text>", kinds=KINDS) -> list[Mention]:
    """The kinds named by the identifiers and string literals of ``source`` (docstrings and
    comments are prose: not scanned)."""
    prose = _prose_lines(source)
    lines = source.splitlines()
    found = []
    for tok in tokenize.generate_tokens(io.StringIO(source).readline):
        if tok.type == tokenize.NAME:
            names = _in_identifier(tok.string, kinds)
        elif tok.type == tokenize.STRING and tok.start[0] not in prose:
            names = _in_text(tok.string, kinds)
        else:
            continue
        found += [Mention(path, tok.start[0], n, tok.string, lines[tok.start[0] - 1])
                  for n in names]
    return found


def scan_lines(text: str, path: str = "<text>", kinds=KINDS) -> list[Mention]:
    """The kinds named by the lines of a Makefile or TOML file, each cut at its comment."""
    found = []
    for n, line in enumerate(text.splitlines(), 1):
        code = line.split("#", 1)[0]
        found += [Mention(path, n, k, line.strip(), line) for k in _in_text(code, kinds)]
    return found


def scan(path: Path) -> list[Mention]:
    rel = str(path.relative_to(ROOT))
    text = path.read_text()
    return scan_python(text, rel) if path.suffix == ".py" else scan_lines(text, rel)


def _excepted(m: Mention) -> bool:
    return any(path == m.path and needle in m.source for path, needle in EXCEPTIONS)


def test_no_module_outside_the_kind_folders_names_a_kind():
    found = [m for p in SCANNED for m in scan(p) if not _excepted(m)]
    assert not found, ("read the kind from phonglab.validate.registry.KINDS (or give the kind's "
                       "folder the part), or list an exception with why:\n"
                       + "\n".join(map(str, found)))


def test_every_exception_is_still_needed():
    mentions = [m for p in SCANNED for m in scan(p)]
    idle = [key for key in EXCEPTIONS
            if not any(m.path == key[0] and key[1] in m.source for m in mentions)]
    assert not idle, f"these exceptions excuse nothing any more; remove them: {idle}"


def test_the_scanned_files_are_there():
    assert all(p.is_file() for p in SCANNED)
    names = {p.name for p in SCANNED}
    assert {"core.py", "sweep.py", "batch.py", "markdown.py", "Makefile"} <= names


#: Two made-up kinds the scanner's own tests plant (independent of which kinds are registered).
TOYS = (Kind(name="gizmo", word="gizmo", plural="gizmos", class_name="Gizmo",
             register="mi.register_gizmo", topics=("finite",), object_type="Gizmo", tag="gizmo"),
        Kind(name="flux", word="flux function", plural="flux functions",
             class_name="FluxFunction", register="mi.register_flux", topics=("finite",),
             object_type="FluxFunction", tag="flux"))


@pytest.mark.parametrize("source, kind", [
    ('if kind == "gizmo":\n    pass\n', "gizmo"),                     # a branch on a kind
    ('x = f"{n} calls mi.register_flux"\n', "flux"),                  # inside an f-string
    ("def scene_gizmo(args):\n    return args\n", "gizmo"),          # an identifier's part
    ("base = mi.SamplingGizmo\n", "gizmo"),                          # a Mitsuba class
    ("base = mi.FluxFunction\n", "flux"),
    ('TITLE = "the built-in flux functions"\n', "flux"),             # a plural
    ('WORD = "Flux function"\n', "flux"),                            # a word, any case
])
def test_the_scanner_catches_a_planted_mention(source, kind):
    assert [m.kind for m in scan_python(source, kinds=TOYS)] == [kind]


def test_the_scanner_reads_no_prose_and_no_other_word():
    source = ('"""A gizmo, a flux function."""\n'
              "def f(x):\n"
              '    """The flux function of a gizmo."""\n'
              "    return x  # a gizmo's\n"
              'NAME = "mygizmo"\n'                    # a plugin's name, not the kind's
              'TEXT = "a fluxion of gizmology"\n')
    assert scan_python(source, kinds=TOYS) == []
    assert scan_lines("tables:  # every gizmo\n\tpython run.py\n", kinds=TOYS) == []
    assert [m.kind for m in scan_lines("x: docs/conformance-gizmos.md --kind flux\n",
                                       kinds=TOYS)] == ["gizmo", "flux"]
