"""phonglab's modules import one another without a circle.

Every ``import`` counts, at the top of a module or inside a function (a lazy import still ties
the two modules together: engine/scenes -> registration -> validate/core -> validate/builtin
-> engine/scenes was such a circle).  ``from X import name`` is an edge to the module
``X.name`` when there is one, else to ``X`` (a package's ``__init__``).  A kind's folder
imports its implementation module lazily (:attr:`phonglab.validate.kind.Kind.implementation`),
so nothing that implementation imports may import the kind's record or the registry back.
"""

from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"


def modules(root: Path = SRC) -> dict[str, tuple[str, bool]]:
    """module name -> (its source, whether it is a package's ``__init__``)."""
    out = {}
    for f in root.rglob("*.py"):
        parts = list(f.relative_to(root).with_suffix("").parts)
        package = parts[-1] == "__init__"
        out[".".join(parts[:-1] if package else parts)] = (f.read_text(), package)
    return out


def graph(mods: dict[str, tuple[str, bool]]) -> dict[str, set[str]]:
    """module -> the modules among ``mods`` it imports."""
    out = {}
    for name, (source, package) in mods.items():
        deps = set()
        for node in ast.walk(ast.parse(source)):
            if isinstance(node, ast.Import):
                deps.update(a.name for a in node.names)
            elif isinstance(node, ast.ImportFrom):
                base = name.split(".") if package else name.split(".")[:-1]
                if node.level:
                    base = base[:len(base) - node.level + 1]
                    target = ".".join(base + ([node.module] if node.module else []))
                else:
                    target = node.module
                for a in node.names:
                    deps.add(f"{target}.{a.name}" if f"{target}.{a.name}" in mods else target)
        out[name] = {d for d in deps if d in mods and d != name}
    return out


def cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), each sorted."""
    index, low, stack, on, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(edges[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(sorted(comp))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return found


def test_phonglab_imports_form_no_circle():
    mods = modules()
    assert "phonglab.validate.core" in mods and len(mods) > 150
    assert cycles(graph(mods)) == []


def test_a_circle_through_a_lazy_import_is_found():
    mods = {"p": ("", True),
            "p.a": ("from . import b\n", False),
            "p.b": ("def f():\n    from .c import g\n", False),
            "p.c": ("from p.a import x\ng = 1\n", False),
            "p.d": ("import p.a\n", False)}
    assert cycles(graph(mods)) == [["p.a", "p.b", "p.c"]]
    mods["p.c"] = ("g = 1\n", False)
    assert cycles(graph(mods)) == []
