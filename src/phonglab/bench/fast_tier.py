r"""The fast tier as a new user meets it: ``make test`` in a fresh clone, timed cold and warm.

``scripts/fast_tier_timing.py`` clones the checkout's ``HEAD`` into a temporary folder, runs
``make setup`` there (the virtual environment and the package, untimed: it is set-up, not
the tests), then ``make test`` (``pytest -m "not slow" -n auto``: the default tier) as a fresh
process:

* **cold**: ``HOME`` an empty folder, so that Dr.Jit's kernel cache (``$HOME/.drjit``, read
  once when Dr.Jit is imported: :mod:`phonglab.parallel.worker`), phonglab's worker caches
  and matplotlib's font cache are empty, as on a machine that never ran phonglab;
* **warm**: the same ``HOME`` again, ``--warm`` times (every kernel compiled by the cold run);
* **own HOME** (``--own-home``): this machine's own ``HOME``, whose kernel cache many earlier
  runs filled -- a developer's machine.  It differs from *warm* because a kernel's IR
  depends on what ran before it in the same process (what is already evaluated, which
  objects exist), and pytest-xdist hands the tests to its workers in an order that changes
  from run to run: a run meets kernels no earlier run compiled.  Measured with an empty
  ``HOME``: ``tests/test_validate_emitter.py`` and ``tests/test_validate_integrator.py``
  each run alone and then again compile nothing new, both in one process then compile 338
  kernels more.  On a smaller scale, ``validate_integrator("direct", topics=["bias"])`` after
  ``validate_emitter("area")`` launches the three distinct kernels it launches in a fresh
  process and two more (a gather from a mesh's index and vertex buffers, split out of the
  render kernel).

Each run records its wall time, pytest's own summary (passed, failed, its seconds) and the
1-minute load average before and after (nothing else should run).  The aims (issue 53): warm
≤ :data:`WARM_TARGET` s and cold ≤ :data:`COLD_TARGET` s on a quiet 2-core machine.
:func:`report_section` renders ``fast_tier.json`` into BENCHMARKS.md.
"""

from __future__ import annotations

import re
import statistics

from .report_data import RunData, fmt_met, part_record

#: The record's name in the bench folder (docs/bench).
JSON_NAME = "fast_tier.json"
#: Aims of the default tier from a fresh clone, seconds on 2 quiet cores (issue 53).
WARM_TARGET = 150.0
COLD_TARGET = 200.0

_SUMMARY = re.compile(r"(?:(\d+) failed, )?(\d+) passed.* in ([\d.]+)s")


def summary(text: str) -> dict:
    """pytest's last summary line of ``text`` -> {"passed", "failed", "pytest_seconds"}
    (None where absent)."""
    found = None
    for line in text.splitlines():
        m = _SUMMARY.search(line)
        if m:
            found = m
    if found is None:
        return {"passed": None, "failed": None, "pytest_seconds": None}
    return {"passed": int(found.group(2)), "failed": int(found.group(1) or 0),
            "pytest_seconds": float(found.group(3))}


def report_section(d: RunData) -> list[str]:
    """BENCHMARKS.md's fast-tier section (empty when ``fast_tier.json`` is not in the bench
    folder)."""
    data = part_record(d, JSON_NAME)
    if not data:
        return []
    runs = data["runs"]
    L = ["\n## The fast tier: `make test` from a fresh clone\n",
         f"`scripts/fast_tier_timing.py` (`make fast-tier-timing`): `git clone` of "
         f"{data['commit']}, `make setup` ({data['setup_seconds']:.0f} s, not counted), then "
         f"`make test` (the default tier, `pytest -m \"not slow\" -n auto`) as a fresh process "
         f"on {data['cores']} cores: cold (an empty `HOME`: Dr.Jit's kernel cache, phonglab's "
         f"worker caches and matplotlib's font cache empty) and then warm, wall time of the "
         f"whole command.\n",
         "| run | wall (s) | pytest (s) | passed | failed | load before → after | aim | met |",
         "|---|---|---|---|---|---|---|---|"]
    for r in runs:
        aim = COLD_TARGET if r["mode"] == "cold" else WARM_TARGET
        r = {**r, "mode": r["mode"] if r["mode"] != "own HOME" else "warm, own `HOME`"}
        L.append(f"| {r['mode']} | {r['seconds']:.1f} | {r['pytest_seconds']} | {r['passed']} | "
                 f"{r['failed']} | {r['load_before']} → {r['load_after']} | ≤ {aim:g} s | "
                 f"{fmt_met(r['seconds'] <= aim and r['failed'] == 0)} |")
    warm = [r["seconds"] for r in runs if r["mode"] == "warm"]
    if warm:
        L.append(f"\nWarm: median {statistics.median(warm):.1f} s over {len(warm)} runs "
                 f"[{min(warm):.1f}, {max(warm):.1f}].")
    if any(r["mode"] == "own HOME" for r in runs):
        L.append("\n*Warm, own `HOME`*: the same clone with this machine's own `HOME`, whose "
                 "Dr.Jit kernel cache many earlier runs filled.  A kernel's IR depends on what "
                 "ran before it in the same process, and pytest-xdist deals the tests to its "
                 "workers in an order that changes from run to run, so the second and third "
                 "runs from an empty `HOME` still compile kernels no earlier run did; a "
                 "long-used cache holds most of them (`phonglab.bench.fast_tier` gives the "
                 "measurements).")
    return L + [""]
