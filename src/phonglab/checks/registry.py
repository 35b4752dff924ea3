"""Running the checks: the registry :data:`CHECKS` and :func:`run_checks`.

The rows are :class:`phonglab.verdict.Row` records; ``phonglab check`` prints and writes them as
a :class:`phonglab.verdict.Report` (:mod:`phonglab.cli.check`).  Each check runs as a validator
topic does (:func:`phonglab.validate.core.guarded`): a plugin under test (``--lambert``,
``--phong``) that raises, calls ``sys.exit``/``os._exit`` or runs past ``--timeout`` is one
failing row of that check, naming the plugin's error and its file:line, and the other checks
still report -- never a traceback, and never the plugin's exit status as the verdict.
"""

from __future__ import annotations

import time
from typing import Callable

from .. import registration
from ..errors import PhonglabError
from ..validate.core import guarded
from ..verdict import Row
from . import CHECK_NAMES
from .common import Config
from .constancy import check_constancy
from .energy import check_energy
from .reflection import check_reflection
from .sanity import check_sanity
from .scene import check_scene
from .snell import check_snell

#: Each check by name; :data:`phonglab.checks.CHECK_NAMES` gives the order of the table.
CHECKS: dict[str, Callable[[Config], list[Row]]] = {
    "energy": check_energy,
    "reflection": check_reflection,
    "scene": check_scene,
    "constancy": check_constancy,
    "snell": check_snell,
    "sanity": check_sanity,
}


def run_checks(names=None, cfg: Config | None = None,
               on_check: Callable[[str], None] | None = None) -> list[Row]:
    """Run the named checks (all by default) in the order of :data:`CHECK_NAMES`."""
    cfg = cfg or Config()
    names = list(names or CHECK_NAMES)
    unknown = [n for n in names if n not in CHECKS]
    if unknown:
        raise PhonglabError(f"unknown check {', '.join(map(repr, unknown))}; choose from "
                            f"{', '.join(CHECK_NAMES)}.")
    registration.register()
    results: list[Row] = []
    for name in [n for n in CHECK_NAMES if n in names]:
        if on_check:
            on_check(name)
        t0 = time.perf_counter()
        rows = guarded(name, lambda: CHECKS[name](cfg))
        for r in rows:
            r.details.setdefault("check_seconds", round(time.perf_counter() - t0, 2))
        results.extend(rows)
    return results
