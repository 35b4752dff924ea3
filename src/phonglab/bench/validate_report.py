"""BENCHMARKS.md's ``phonglab validate`` section: wall time per plugin and the topics that take
it (``scripts/validate_timing.py --json`` writes ``validate.json``), and the medians before and
after a change (``validate-before.json``: the same script at an earlier commit).
"""

from __future__ import annotations

import statistics

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
         "dict (its parameters pinned: one point). Topics: seconds of the default run's "
         "profile (`validate --profile`, summed over the sweep's points), the three largest. "
         "Points: the sweep's, and where the automatic runner spread them over worker "
         "processes (the given point here, the rest on the free cores when they would take "
         "≥ 20 s: docs/validate.md) the processes; the profile then sums every process's "
         "time. "
         "Targets on 2 cores: a BSDF ≤ 20 s default and ≤ 5 s `--quick`, an integrator ≤ 45 s "
         "and ≤ 10 s.\n",
         "| plugin | kind | points | default (s) | met | --quick (s) | met | largest topics "
         "(default, s) |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        cells = []
        for i, mode in enumerate(("default", "quick")):
            v = r[f"{mode}_seconds"]
            med = statistics.median(v)
            target = (r.get("targets") or (None, None))[i]
            cells += [f"{med:.1f} [{min(v):.1f}, {max(v):.1f}]",
                      "—" if target is None else fmt_met(med <= target)]
        top = sorted(r["profile_default"].items(), key=lambda kv: -kv[1])[:3]
        name = r["plugin"] + (f" ({r['variant']})" if r["variant"] != "llvm_ad_rgb" else "")
        workers = (r.get("where") or {}).get("workers", 1)
        points = f"{r['points']}" + (f" ({workers} processes)" if workers > 1 else "")
        L.append(f"| {name} | {r['kind']} | {points} | " + " | ".join(cells)
                 + f" | {', '.join(f'{t} {s:.1f}' for t, s in top)} |")
    return L + _misses(rows) + _validate_before_after(d, rows) + [""]


def _misses(rows) -> list[str]:
    """Where the plugins that miss a target spend their default run: the share of the profile
    in its two largest topics, and which topics those are."""
    missed = []
    for r in rows:
        targets = r.get("targets") or (None, None)
        meds = [statistics.median(r[f"{m}_seconds"]) for m in ("default", "quick")]
        if any(t is not None and m > t for t, m in zip(targets, meds)) and r["profile_default"]:
            top = sorted(r["profile_default"].items(), key=lambda kv: -kv[1])[:2]
            total = sum(r["profile_default"].values())
            missed.append((r["plugin"], [t for t, _ in top], sum(v for _, v in top) / total))
    if not missed:
        return []
    names = sorted({t for _, tops, _ in missed for t in tops})
    shares = [share for _, _, share in missed]
    return [f"\n{len(missed)} plugins miss a target; in each, two topics ({', '.join(names)} "
            f"among them) take {min(shares):.0%}–{max(shares):.0%} of the profiled time, at every "
            f"point of the sweep (the column `points`).\n"]


def _validate_before_after(d: RunData, rows) -> list[str]:
    """Medians before -> after for the plugins ``validate-before.json`` (the same script at an
    earlier commit, ``{"commit": what was timed, "rows"}``) also timed."""
    before = part_record(d, "validate-before.json")
    if not before:
        return []
    def key(r):                     # one plugin may be timed in several variants
        return r["plugin"], r.get("variant", "llvm_ad_rgb")

    after = {key(r): r for r in rows}
    L = [f"\nBefore and after: medians at commit {before['commit']} against this table "
         f"(the same script and machine); the ratio is after / before.\n",
         "| plugin | default before → after (s) | ratio | --quick before → after (s) | ratio |",
         "|---|---|---|---|---|"]
    for b in before["rows"]:
        a = after.get(key(b))
        if a is None:
            continue
        cells = []
        for mode in ("default", "quick"):
            mb = statistics.median(b[f"{mode}_seconds"])
            ma = statistics.median(a[f"{mode}_seconds"])
            cells += [f"{mb:.1f} → {ma:.1f}", f"{ma / mb:.2f}"]
        variant = key(b)[1]
        name = b["plugin"] + (f" ({variant})" if variant != "llvm_ad_rgb" else "")
        L.append(f"| {name} | " + " | ".join(cells) + " |")
    return L
