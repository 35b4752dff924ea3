"""BENCHMARKS.md's ``phonglab validate`` section: wall time per plugin and the topics that take
it (``scripts/validate_timing.py --json`` writes ``validate.json``), and the medians before and
after a change (``validate-before.json``: the same script at an earlier commit).
"""

from __future__ import annotations

import statistics

from ..parallel import AUTO_MIN_SECONDS
from .report_data import RunData, fmt_met, part_record


def validate_section(d: RunData) -> list[str]:
    """``phonglab validate`` wall times per plugin and the topics that take them
    (``scripts/validate_timing.py --json``)."""
    rows = part_record(d, "validate.json")
    if rows is None:
        return []
    L = ["\n## `phonglab validate`: wall time per plugin, and where it goes\n",
         "`scripts/validate_timing.py` (run by `make bench`): a fresh `phonglab validate NAME` "
         "process per run (start-up, kernels, every topic of the sweep; Dr.Jit's kernel cache "
         "warm), default and `--quick` alternately, median [min, max] over the repeats; a "
         "wrapper BSDF that needs a nested one is its conformance case given to `validate` as a "
         "dict (its parameters pinned: one point). Topics: seconds of each mode's first run's "
         "profile (`validate --profile`, summed over the sweep's points), the three largest. "
         "Points: the sweep's, and where the automatic runner spread them over worker "
         "processes (the given point here, the rest on the free cores when they are "
         f"predicted to save ≥ {AUTO_MIN_SECONDS:g} s: docs/validate.md) the processes; the "
         "profile then sums every process's time. "
         "Targets on 2 cores: a BSDF ≤ 20 s default and ≤ 5 s `--quick`, an integrator ≤ 45 s "
         "and ≤ 10 s.\n",
         "| plugin | kind | points | default (s) | met | --quick (s) | met | largest topics "
         "(default, s) | largest topics (--quick, s) |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        cells = []
        for i, mode in enumerate(("default", "quick")):
            v = r[f"{mode}_seconds"]
            med = statistics.median(v)
            target = (r.get("targets") or (None, None))[i]
            cells += [f"{med:.1f} [{min(v):.1f}, {max(v):.1f}]",
                      "—" if target is None else fmt_met(med <= target)]
        tops = [", ".join(f"{t} {v:.1f}" for t, v in
                          sorted((r.get(f"profile_{m}") or {}).items(), key=lambda kv: -kv[1])[:3])
                or "—" for m in ("default", "quick")]
        name = _name(r)
        workers = (r.get("where") or {}).get("workers", 1)
        points = f"{r['points']}" + (f" ({workers} processes)" if workers > 1 else "")
        L.append(f"| {name} | {r['kind']} | {points} | " + " | ".join(cells + tops) + " |")
    return L + _when(rows) + _misses(rows) + _validate_before_after(d, rows) + [""]


def _when(rows) -> list[str]:
    """When the rows were timed, where they were not all timed in one run (``measured``:
    ``scripts/validate_timing.py`` records it; older rows lack it)."""
    groups: dict = {}
    for r in rows:
        groups.setdefault(r.get("measured"), []).append(_name(r))
    if len(groups) < 2:
        return []
    return ["\nTimed " + "; ".join(
        f"{when or 'in an earlier run (before the script recorded when)'}: {', '.join(names)}"
        for when, names in sorted(groups.items(), key=lambda kv: kv[0] or "")) + ".\n"]


def _key(r) -> tuple[str, str]:
    """A row's plugin and variant (one plugin may be timed in several variants)."""
    return r["plugin"], r.get("variant", "llvm_ad_rgb")


def _name(r) -> str:
    """A row's plugin, with its variant where that is not llvm_ad_rgb."""
    plugin, variant = _key(r)
    return plugin + (f" ({variant})" if variant != "llvm_ad_rgb" else "")


def _misses(rows) -> list[str]:
    """Where each plugin that misses a target spends the run that misses it: per missed mode,
    the two largest topics of its profile and their share, and the points they repeat at."""
    lines, shares = [], []
    for r in rows:
        targets = r.get("targets") or (None, None)
        said = []
        for mode, target in zip(("default", "quick"), targets):
            med = statistics.median(r[f"{mode}_seconds"])
            profile = r.get(f"profile_{mode}") or {}
            if target is None or med <= target or not profile:
                continue
            top = sorted(profile.items(), key=lambda kv: -kv[1])[:2]
            share = sum(v for _, v in top) / sum(profile.values())
            shares.append(share)
            # the profile sums every process's time: spread evenly over the processes, the
            # two topics alone still take this long
            where = r.get("where" if mode == "default" else "where_quick")
            workers = (where or {}).get("workers")
            alone = sum(v for _, v in top) / workers if workers else 0.0
            said.append(f"{'--quick' if mode == 'quick' else 'default'} {med:.1f} s > "
                        f"{target:g} s: " + " + ".join(f"{t} {v:.1f} s" for t, v in top)
                        + f" ({share:.0%} of the profile"
                        + (f"; {alone:.1f} s alone on {workers} process"
                           f"{'es' if workers > 1 else ''}, above the target"
                           if alone > target else "") + ")")
        if said:
            lines.append(f"- {_name(r)}, {r['points']} points: " + "; ".join(said))
    if not lines:
        return []
    return [f"\n{len(lines)} plugins miss a target; in each missed run two topics take "
            f"{min(shares):.0%}–{max(shares):.0%} of the profiled time, at every point of the "
            f"sweep:\n", *lines, ""]


def _validate_before_after(d: RunData, rows) -> list[str]:
    """Medians before -> after for the plugins ``validate-before.json`` (the same script at an
    earlier commit, ``{"commit": what was timed, "rows"}``) also timed."""
    before = part_record(d, "validate-before.json")
    if not before:
        return []
    after = {_key(r): r for r in rows}
    L = [f"\nBefore and after: medians at commit {before['commit']} against this table "
         f"(the same script and machine); the ratio is after / before.\n",
         "| plugin | default before → after (s) | ratio | --quick before → after (s) | ratio |",
         "|---|---|---|---|---|"]
    for b in before["rows"]:
        a = after.get(_key(b))
        if a is None:
            continue
        cells = []
        for mode in ("default", "quick"):
            mb = statistics.median(b[f"{mode}_seconds"])
            ma = statistics.median(a[f"{mode}_seconds"])
            cells += [f"{mb:.1f} → {ma:.1f}", f"{ma / mb:.2f}"]
        L.append(f"| {_name(b)} | " + " | ".join(cells) + " |")
    return L
