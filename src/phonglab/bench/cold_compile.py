"""Cold JIT compile times: the kernels compiled in a fresh process with an empty kernel cache.

In the bench process the render kernels are already built by the reference renders of the
same scene (their first call is a cache hit), so :func:`sweep_cold_compile` runs
:func:`cold_probe` in a subprocess whose ``$HOME`` (where Dr.Jit keeps its kernel cache,
``$HOME/.drjit``) is an empty temporary folder, and adds the compile times it reports to
the ``cold_compile_ms`` column of ``jit.csv``.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from .. import registration
from ..errors import PhonglabError
from ..physics.estimators import METHODS, ReflectionEstimators
from .config import ESTIMATOR_SCENES, VARIANT
from .cornell import render_jit, render_setups
from .csvlog import fmt_value, open_log

#: Marks the probe's result line on its standard output.
PROBE_TAG = "COLD"


def cold_probe() -> dict[str, float]:
    """Compile ms of every bench render (8 px) and estimator, printed as ``COLD{json}``."""
    registration.register(VARIANT)
    out = {}
    for methods in render_setups(res=8).values():
        for method, (spec, _) in methods.items():
            _, ms, _, _ = render_jit(spec.load(VARIANT), 1, 7)
            out["render/" + method] = ms
    est = ReflectionEstimators(ESTIMATOR_SCENES["disk3 p=100"])
    for m in METHODS:
        out["estimator/" + m] = est.run(m, 256, seed=1).compile_ms
    print(PROBE_TAG + json.dumps(out), flush=True)
    return out


def sweep_cold_compile(out: Path, progress: bool = True) -> None:
    """Cold JIT compile times: a subprocess with an empty Dr.Jit kernel cache ($HOME/.drjit)."""
    log = open_log(out, "jit")
    if log.rows and all(r["cold_compile_ms"] for r in log.rows if r["group"] in ("render", "estimator")):
        return
    code = "from phonglab.bench.cold_compile import cold_probe; cold_probe()"
    with tempfile.TemporaryDirectory(prefix="phonglab-cold-") as home:
        env = dict(os.environ, HOME=home, MPLCONFIGDIR=home)
        proc = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                              text=True, timeout=600)
    line = next((ln for ln in proc.stdout.splitlines() if ln.startswith(PROBE_TAG)), None)
    if proc.returncode != 0 or line is None:
        raise PhonglabError(f"the cold-compile probe failed (exit {proc.returncode}): "
                            f"{proc.stderr.strip().splitlines()[-1:] or proc.stdout[-300:]}")
    cold = json.loads(line[len(PROBE_TAG):])
    for r in log.rows:
        key = f"{r['group']}/{r['method']}"
        if key in cold:
            r["cold_compile_ms"] = fmt_value(float(cold[key]))
    log.rewrite()
