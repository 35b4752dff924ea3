"""Lazy re-exports for a package's public API (PEP 562 module ``__getattr__``).

``phonglab`` builds every subcommand's parser at start-up, which imports ``phonglab.checks``
and ``phonglab.bench``; importing their submodules there would load Mitsuba, scipy and
matplotlib (one to two seconds) for every command, ``--help`` included.  Such a package
names its public API once and resolves each name from its home module on first use::

    __getattr__, __dir__ = lazy_exports(__name__, {"report": ("run_checks",), ...})
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Iterable, Mapping


def lazy_exports(package: str, exports: Mapping[str, Iterable[str]]
                 ) -> tuple[Callable[[str], object], Callable[[], list[str]]]:
    """``__getattr__`` and ``__dir__`` for ``package``: ``exports`` maps submodule -> its public names."""
    home = {name: module for module, names in exports.items() for name in names}
    namespace = importlib.import_module(package).__dict__

    def __getattr__(name: str):
        module = home.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f"{package}.{module}"), name)
        namespace[name] = value
        return value

    def __dir__() -> list[str]:
        return sorted(set(namespace) | set(home))

    return __getattr__, __dir__
