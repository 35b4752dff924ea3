"""The planner benchmark's table: planned vs default configuration at equal error.

The rows come from ``scripts/planner_bench.py``; :mod:`phonglab.bench` puts the table in
BENCHMARKS.md.  Efficiency ratio = (T·E²)_default / (T·E²)_planned, the time ratio at exactly
equal error when the error is noise-dominated (E. Veach, *Robust Monte Carlo Methods for Light
Transport Simulation*, PhD thesis, Stanford 1997, §2.4.3; *Physically Based Rendering*, 4th
ed., §2.1.4).
"""

from __future__ import annotations


def benchmark_table(rows: list[dict]) -> str:
    """Markdown table of ``scripts/planner_bench.py`` rows (planned vs default at equal error)."""
    out = ["| scene | default (rgb, depth 8, scene spp): time, error | planned: variant, depth, "
           "spp | planned: time (predicted), error (predicted) | speed-up | efficiency ratio "
           "| pilot |",
           "|---|---|---|---|---|---|---|"]
    for r in rows:
        d, p = r["default"], r["planned"]
        out.append(
            f"| {r['scene']} ({r['res']}²) | {d['seconds_median'] * 1e3:.0f} ms, "
            f"{d['error']:.4f} ± {d['error_sd']:.4f} | {p['variant']}, {p['max_depth']}, "
            f"{p['spp']} | {p['seconds_median'] * 1e3:.0f} ms "
            f"({p['predicted_seconds_one_pass'] * 1e3:.0f}), {p['error']:.4f} ± "
            f"{p['error_sd']:.4f} ({p['predicted_error']:.4f}) | {r['speedup']:.2f}x | "
            f"{r['efficiency_ratio']:.2f}x | "
            f"{p['pilot_seconds']:.1f} s |")
    return "\n".join(out)
