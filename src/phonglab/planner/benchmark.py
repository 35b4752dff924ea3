"""The planner benchmark's table: the planned command against the default one at equal error.

The rows come from ``scripts/planner_bench.py``: per scene a target error E, the default
configuration (llvm_ad_rgb, path at max_depth 8, uniform spp raised until it reaches E) and
``phonglab render --target-error E`` (plan + render), each timed as a whole fresh process
(start-up, JIT compilation, pilot and planning included); :mod:`phonglab.bench` puts the
table in BENCHMARKS.md.  Speed-up = median T_default / median T_planned, with the min-max of
the per-seed ratios.

**The default's spp at E.**  A uniform render of N samples per pixel at a fixed max_depth
has the expected squared relative error e(N)² = b² + c/N: its depth bias b (the bounces the
depth omits; it does not fall with N) and its noise c/N (Monte Carlo variance, ∝ 1/N).
:func:`fit_error_model` fits (b², c) to measured (N, e) pairs and :func:`spp_for_error`
solves e(N) = E for N; a noise-only correction N·(e/E)² (the bench's rule before) stops
short wherever b is a sizeable part of E (glass_slab at depth 8: b ≈ 0.035 of E = 0.05, so
795 spp gave 0.053, not 0.05; measured).

**At equal error, conservatively.**  Both commands' errors scatter about E over seeds.  The
row's speed-up at equal error (:func:`equal_error_speedup`) charges the planned command
(e_p/E)² more time when its mean error e_p is above E and the default (e_d/E)² less when
its mean error e_d is below E, never the reverse.  Both factors scale the whole command's
time, fixed start-up included, and ignore the default's bias, and each of these makes the
correction larger than the true one: the figure can only understate the planner's speed-up.
"""

from __future__ import annotations

import math

import numpy as np


def fit_error_model(points) -> tuple[float, float]:
    """(b², c) of e(N)² = b² + c/N fitted to ``points`` [(N, e), ...] (e: relative RMSE).

    Least squares in e² against 1/N, each residual relative to its own e² (a point's
    measured e² is about equally precise in relative terms whatever N is).  One point, a
    non-positive slope (noise swamped the difference) or a negative intercept fall back to
    the noise-only model through the point of most samples (b² = 0, c = N·e²); b² is
    otherwise at least 0.
    """
    pts = sorted((float(n), float(e)) for n, e in points)
    n_last, e_last = pts[-1]
    noise_only = (0.0, n_last * e_last * e_last)
    if len(pts) < 2:
        return noise_only
    x = np.array([1.0 / n for n, _ in pts])
    y = np.array([e * e for _, e in pts])
    if np.ptp(x) == 0.0 or not np.all(y > 0):
        return noise_only
    c, b2 = np.polyfit(x, y, 1, w=1.0 / y)
    if c <= 0.0 or b2 < 0.0:
        return noise_only
    return float(b2), float(c)


def spp_for_error(b2: float, c: float, target: float) -> float:
    """N with b² + c/N = target², or ``math.inf`` when the bias alone reaches the target."""
    room = target * target - b2
    return c / room if room > 0.0 else math.inf


def equal_error_speedup(row: dict) -> float:
    """The row's speed-up at equal error, conservatively (module docstring): median
    T_default/T_planned × min(1, (E/e_planned)²) × min(1, (e_default/E)²)."""
    target = row["target_error"]
    e_plan, e_def = row["planned"]["error"], row["default"]["error"]
    over = min(1.0, (target / e_plan) ** 2) if e_plan > 0 else 1.0
    under = min(1.0, (e_def / target) ** 2)
    return row["speedup"] * over * under


def benchmark_table(rows: list[dict]) -> str:
    """Markdown table of ``scripts/planner_bench.py`` rows (whole-command wall time)."""
    out = ["| scene | E | default: spp, error, time | planned: render, variant, depth, spp | "
           "planned: error, time (pilot) | speed-up (min-max over seeds) | at equal error |",
           "|---|---|---|---|---|---|---|"]
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
            f"({r['speedup_min']:.2f}-{r['speedup_max']:.2f}) | "
            f"{equal_error_speedup(r):.2f}x |")
    tuned = [r for r in rows if not r.get("held_out")]
    held = [r for r in rows if r.get("held_out")]
    for label, group in (("the rows it was tuned on", tuned), ("the held-out rows", held)):
        if not group:
            continue
        fast = sum(equal_error_speedup(r) >= FAST for r in group)
        never = sum(equal_error_speedup(r) >= NEVER_LOSES for r in group)
        out.append(f"\nOn {label}: at least {NEVER_LOSES:g}x the default's speed at equal error "
                   f"(median, corrected conservatively for the errors' scatter about E) on "
                   f"{never} of {len(group)}, at least {FAST:g}x on {fast} of {len(group)}.")
    out.append("\n" + promise_table(rows))
    return "\n".join(out)


#: The planner's targets: the planned command never slower than this fraction of the default
#: at equal error, and at least FAST times faster on most rows.
NEVER_LOSES, FAST = 0.95, 1.5
#: The error promise: every planned render's achieved error within these fractions of E.
PROMISE_HIGH, PROMISE_LOW = 1.1, 0.8


def promise_table(rows: list[dict]) -> str:
    """Markdown table: each row's achieved error over E per seed of the planned command (the
    error promise: at most :data:`PROMISE_HIGH`, at least :data:`PROMISE_LOW` where the
    budget allows), with the route the plan took."""
    out = [f"| scene | route | achieved / E per seed | ≤ {PROMISE_HIGH:g} E | "
           f"≥ {PROMISE_LOW:g} E |", "|---|---|---|---|---|"]
    for r in rows:
        p, target = r["planned"], r["target_error"]
        ratios = [e / target for e in p.get("errors", [p["error"]])]
        route = f"{p['sampling']}" + (" + pilot" if p.get("reused_spp") else "")
        out.append(f"| {r['scene']} ({_film(r)}) | {route} | "
                   f"{', '.join(f'{x:.3f}' for x in ratios)} | "
                   f"{'met' if max(ratios) <= PROMISE_HIGH else '**missed**'} | "
                   f"{'met' if min(ratios) >= PROMISE_LOW else '**missed**'} |")
    return "\n".join(out)


def _film(row: dict) -> str:
    """The film size of a row: W×H when its scene parameters give width and height, else R²."""
    params = row.get("params") or {}
    if "width" in params and "height" in params:
        return f"{params['width']}×{params['height']}"
    return f"{row['res']}²"
