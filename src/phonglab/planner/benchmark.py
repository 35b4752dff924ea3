"""The planner benchmark's table: the planned command against the default one at equal error.

The rows come from ``scripts/planner_bench.py``: per scene a target error E, the default
configuration (llvm_ad_rgb, path at max_depth 8, uniform spp raised until it reaches E) and
``phonglab render --target-error E`` (plan + render), each timed as a whole fresh process
(start-up, JIT compilation, pilot and planning included); :mod:`phonglab.bench` puts the
table in BENCHMARKS.md.  Speed-up = median T_default / median T_planned, with the min-max of
the per-seed ratios.
"""

from __future__ import annotations


def benchmark_table(rows: list[dict]) -> str:
    """Markdown table of ``scripts/planner_bench.py`` rows (whole-command wall time)."""
    out = ["| scene | E | default: spp, error, time | planned: render, variant, depth, spp | "
           "planned: error, time (pilot) | speed-up (min-max over seeds) |",
           "|---|---|---|---|---|---|"]
    for r in rows:
        d, p = r["default"], r["planned"]
        sampler = p.get("sampler", "independent")
        render = f"{p['model']} {p['sampling']}" + (f" ({sampler})" if sampler != "independent"
                                                    else "")
        out.append(
            f"| {r['scene']} ({_film(r)}) | {r['target_error']:g} | {d['spp']} spp, "
            f"{d['error']:.4f}, {d['seconds_median']:.2f} s | {render}, "
            f"{p['variant']}, {p['max_depth']}, {p['spp']:.1f} | {p['error']:.4f}, "
            f"{p['seconds_median']:.2f} s ({p['pilot_seconds']:.1f} s) | {r['speedup']:.2f}x "
            f"({r['speedup_min']:.2f}-{r['speedup_max']:.2f}) |")
    fast = sum(r["speedup"] >= 1.5 for r in rows)
    out.append(f"\nPlanned at least 1.5x faster (median) on {fast} of {len(rows)} rows.")
    return "\n".join(out)


def _film(row: dict) -> str:
    """The film size of a row: W×H when its scene parameters give width and height, else R²."""
    params = row.get("params") or {}
    if "width" in params and "height" in params:
        return f"{params['width']}×{params['height']}"
    return f"{row['res']}²"
