"""Every dotted reference in src/'s docstrings and comments names something that exists.

A reference is a Sphinx role (``:mod:``, ``:func:``, ``:class:``, ``:data:``, ``:attr:``,
``:meth:``, ``:exc:``, ``:obj:``, with or without ``~`` and a ``title <target>``) or a
``phonglab.x.y``, backticked or not.  It resolves when it is an importable module or an
attribute reached from one (a dataclass field, an annotated class attribute or a ``self.<name>``
its methods assign counts).  A target that starts with ``.`` is relative: to the module's
package (the package itself for an ``__init__``), else to the module; each further dot is one
package up.  A bare name is looked up in the module, else in a class the docstring or comment
lies in, else among Python's builtins.  Dotted targets of other libraries (``mi.``, ``dr.``,
``np.``) are not checked.
"""

from __future__ import annotations

import ast
import builtins
import importlib
import inspect
import io
import re
import tokenize
from dataclasses import dataclass
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"

#: ``:role:`target``` / ``:role:`~target``` / ``:role:`title <target>```.
ROLE = re.compile(r":(?:mod|func|class|data|attr|meth|exc|obj):"
                  r"`(?:[^`<]*<)?~?([\w.]+?)(?:\(\))?>?`")
#: ``phonglab.x.y`` in single or double backticks.
TICKED = re.compile(r"(?<!:)``?~?(phonglab(?:\.\w+)+)(?:\(\))?``?")
#: phonglab.x.y in plain text (not a path: no ``/`` on either side).
BARE = re.compile(r"(?<![\w/.`~<-])(phonglab(?:\.\w+)+)(?![\w/`>-])")

#: References in modules another change is reworking (planner/, validate/gradient.py), fixed
#: there: each must still fail to resolve, so that its line goes with the fix.
ELSEWHERE: set = set()


@dataclass(frozen=True)
class Reference:
    target: str          #: as written, without ``~`` and ``()``
    module: str          #: the dotted name of the module it is written in
    line: int
    classes: tuple[str, ...] = ()   #: qualified names of the classes it lies in, innermost last

    def __str__(self) -> str:
        return f"{self.module}:{self.line}: {self.target}"


def module_name(path: Path, root: Path = SRC) -> str:
    parts = list(path.relative_to(root).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _targets(text: str) -> list[str]:
    return [m.group(1) for pattern in (ROLE, TICKED, BARE) for m in pattern.finditer(text)]


def _class_spans(tree: ast.AST) -> list[tuple[int, int, str]]:
    """(first line, last line, qualified name) of every class, outer ones first."""
    spans = []

    def walk(node, prefix):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.ClassDef):
                name = prefix + child.name
                spans.append((child.lineno, child.end_lineno, name))
                walk(child, name + ".")
            elif isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                walk(child, prefix)
    walk(tree, "")
    return spans


def references(source: str, module: str) -> list[Reference]:
    """The references in ``source``'s docstrings (module, class, function) and comments."""
    tree = ast.parse(source)
    spans = _class_spans(tree)

    def classes_at(line: int) -> tuple[str, ...]:
        return tuple(name for a, b, name in spans if a <= line <= b)

    texts: list[tuple[int, str]] = []
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            doc = ast.get_docstring(node, clean=False)
            if doc is not None:
                texts.append((node.body[0].lineno, doc))
    for tok in tokenize.generate_tokens(io.StringIO(source).readline):
        if tok.type == tokenize.COMMENT:
            texts.append((tok.start[0], tok.string))
    return [Reference(t, module, line, classes_at(line)) for line, text in texts
            for t in _targets(text)]


def _instance_attributes(klass: type) -> set[str]:
    """The names a class's methods assign as ``self.<name>``."""
    try:
        tree = ast.parse(inspect.cleandoc("\n" + inspect.getsource(klass)))
    except (OSError, TypeError, SyntaxError):
        return set()
    return {node.attr for node in ast.walk(tree)
            if isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store)
            and isinstance(node.value, ast.Name) and node.value.id == "self"}


def _attr(obj, name: str):
    """``getattr`` that also finds a dataclass field, an annotated class attribute or an
    instance attribute its methods assign."""
    if hasattr(obj, name):
        return getattr(obj, name)
    if isinstance(obj, type):
        for klass in obj.__mro__:
            if name in getattr(klass, "__dataclass_fields__", {}) or \
                    name in getattr(klass, "__annotations__", {}) or \
                    name in _instance_attributes(klass):
                return _FIELD
    raise AttributeError(name)


_FIELD = object()


def resolve_absolute(target: str) -> bool:
    """Whether ``target`` (``a.b.c``) is a module, or an attribute path from the longest
    importable module prefix."""
    parts = target.split(".")
    for k in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:k]))
        except ImportError:
            continue
        try:
            for name in parts[k:]:
                obj = _attr(obj, name)
        except AttributeError:
            return False
        return True
    return False


def resolves(ref: Reference, is_package: bool = False) -> bool:
    """Whether ``ref`` names something that exists (see the module docstring)."""
    target = ref.target
    if target.startswith("."):
        rest = target.lstrip(".")
        up = len(target) - len(rest) - 1          # ``..x``: the package's parent's x
        package = ref.module if is_package else ref.module.rpartition(".")[0]
        bases = [package.rsplit(".", up)[0] if up else package] + ([ref.module] if not up else [])
        return any(resolve_absolute(f"{base}.{rest}") for base in bases)
    if target.startswith("phonglab.") or target == "phonglab":
        return resolve_absolute(target)
    if "." in target and target.split(".")[0] not in _module_globals(ref.module):
        return True                  # another library's (mi.Float, np.random, ...)
    scopes = [ref.module] + [f"{ref.module}.{c}" for c in reversed(ref.classes)]
    return any(resolve_absolute(f"{scope}.{target}") for scope in scopes) or \
        ("." not in target and hasattr(builtins, target))


def _module_globals(module: str) -> set[str]:
    return set(vars(importlib.import_module(module)))


def all_references() -> list[tuple[Reference, bool]]:
    out = []
    for path in sorted((SRC / "phonglab").rglob("*.py")):
        module = module_name(path)
        out += [(ref, path.name == "__init__.py")
                for ref in references(path.read_text(encoding="utf-8"), module)]
    return out


# --- the resolver ----------------------------------------------------------------------------

PLANTED = '''"""A module.  :mod:`phonglab.validate.config`, :func:`.config.perturb`,
``phonglab.optics``, :func:`phonglab.validate.roundoff.perturb`, :mod:`.lobes`, from
phonglab.physics.optics.refract and phonglab.figures.optics, not src/phonglab/probe.py,
:class:`~phonglab.validate.conformance.Finding`, :func:`missing_here`, :attr:`kind`."""

class Options:
    """:attr:`normalization_samples` and :attr:`nowhere`."""
    # :data:`phonglab.stats.ALPHA` and ``phonglab.stats.NO_SUCH``
'''


def test_the_resolver_finds_references_and_refuses_stale_ones():
    refs = {r.target: r for r in references(PLANTED, "phonglab.validate.bsdf.planted")}
    assert set(refs) == {"phonglab.validate.config", ".config.perturb", "phonglab.optics",
                         "phonglab.validate.roundoff.perturb", ".lobes",
                         "phonglab.validate.conformance.Finding", "missing_here", "kind",
                         "normalization_samples", "nowhere", "phonglab.stats.ALPHA",
                         "phonglab.stats.NO_SUCH", "phonglab.physics.optics.refract",
                         "phonglab.figures.optics"}
    assert refs["nowhere"].classes == ("Options",) and refs["kind"].classes == ()
    assert refs["phonglab.stats.ALPHA"].line == 8
    stale = {"phonglab.validate.config", ".config.perturb", "phonglab.optics",
             "phonglab.stats.NO_SUCH", "phonglab.figures.optics"}
    for target in stale:
        assert not resolves(refs[target]), target
    for target in ("phonglab.validate.roundoff.perturb", ".lobes", "phonglab.stats.ALPHA",
                   "phonglab.physics.optics.refract", "phonglab.validate.conformance.Finding"):
        assert resolves(refs[target]), target


def test_relative_and_bare_names_resolve_in_their_module_and_package():
    at = Reference(".lanes.INCIDENCES", "phonglab.validate.phase.kind", 1)
    assert resolves(at)
    assert not resolves(Reference(".lanes.NO_SUCH", "phonglab.validate.phase.kind", 1))
    assert resolves(Reference(".registry", "phonglab.validate", 1), is_package=True)
    assert not resolves(Reference(".builtins", "phonglab.validate", 1), is_package=True)
    assert resolves(Reference(".builtin", "phonglab.validate", 1), is_package=True)
    # a name the module does not define (the package face does)
    assert not resolves(Reference("validate_phase", "phonglab.validate.phase.kind", 1))
    assert resolves(Reference("phonglab.validate.validate_phase", "phonglab.validate.phase", 1))
    # ``..``: the package's parent's, an __init__'s package being itself
    assert resolves(Reference("..sphere_bins.Grid", "phonglab.validate.bsdf.signatures", 1))
    assert not resolves(Reference("..lobes", "phonglab.validate.bsdf.signatures", 1))
    assert resolves(Reference("..sphere_bins", "phonglab.validate.bsdf", 1), is_package=True)
    assert not resolves(Reference("..sphere_bins", "phonglab.validate.bsdf", 1))
    # a bare name: the module's, else the enclosing class's (a dataclass field counts)
    assert resolves(Reference("lobe_quadrature", "phonglab.physics.quadrature", 1))
    field = Reference("normalization_samples", "phonglab.validate.bsdf.config", 1, ("Options",))
    assert resolves(field)
    assert not resolves(Reference("normalization_samples", "phonglab.validate.bsdf.config", 1))


def test_module_names_follow_the_files():
    assert module_name(SRC / "phonglab" / "validate" / "__init__.py") == "phonglab.validate"
    assert module_name(SRC / "phonglab" / "validate" / "core.py") == "phonglab.validate.core"


# --- src/ ------------------------------------------------------------------------------------

def test_every_reference_in_src_resolves():
    refs = all_references()
    assert len(refs) > 1000                 # the collector sees src/'s references at all
    stale = [ref for ref, is_package in refs if not resolves(ref, is_package)]
    assert [str(r) for r in stale if (r.module, r.target) not in ELSEWHERE] == []
    assert {(r.module, r.target) for r in stale} == ELSEWHERE

