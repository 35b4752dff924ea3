r"""What the bench's CSV rows add up to: verdicts, ratios, efficiencies, slopes, Pareto fronts.

* Stability verdict (:func:`stability_verdict`): a cell "breaks down" when NaN/Inf appear,
  the relative RMSE exceeds :data:`~phonglab.bench.config.BREAKDOWN_REL_RMSE`, or an error of
  more than :data:`~phonglab.bench.config.BIAS_FLOOR` is not explained by the estimator's own
  standard error: |z| > z_crit, the two-sided :data:`phonglab.stats.ALPHA` level
  Šidák-corrected over every cell (:func:`stability_z_crit`), or a "silent" failure where no
  sample found the light and the reported standard error is 0.
* Efficiency (:func:`efficiency_ratios`): an unbiased estimator's error after time T is
  √(σ² t/T), so the time to reach a given error is proportional to σ²·t per sample.
* MIS against the better single strategy (:func:`mis_ratios`): at equal time
  √(σ²_mis t_mis / min σ²_k t_k), at equal samples √(σ²_mis / min σ²_k).  Veach's bound
  (thesis, Thm. 9.2) is additive in μ², so against a near-zero-variance strategy no fixed
  split stays within a factor; those cells are reported apart.
* Render-time ratios (:func:`ratio_summary`): the median of per-pair ratios of ABBA-ordered
  A/B renders (drift and other processes cancel within a pair).
* Convergence (:func:`loglog_slope`): the OLS slope of log RMSE on log N (−½ for an unbiased
  Monte Carlo estimator).
"""

from __future__ import annotations

import math
from typing import Any, Iterable

import numpy as np

from ..stats import ALPHA, z_critical
from .config import BIAS_FLOOR, BREAKDOWN_REL_RMSE, NEAR_ZERO_REL_SD, RATIO_COMPARISONS, STABILITY_CELLS
from .csvlog import number


def pareto_front(points: Iterable[tuple[float, float]]) -> list[tuple[float, float]]:
    """Points (time, error) not dominated by another (no other is both faster and more accurate),
    sorted by time."""
    pts = sorted({(t, e) for t, e in points if math.isfinite(t) and math.isfinite(e) and e > 0})
    front, best = [], math.inf
    for t, e in pts:
        if e < best:
            front.append((t, e))
            best = e
    return front


def stability_z_crit() -> float:
    """Two-sided normal quantile at ALPHA, Šidák-corrected over every stability cell."""
    return z_critical(ALPHA, STABILITY_CELLS)


def stability_verdict(rel_rmse: float, rel_bias: float, bias_z: float, nonfinite: int,
                      z_crit: float) -> tuple[str, str]:
    """("ok" | "breaks down", reason) by the rule stated in the module docstring.

    A significant bias (|z| > z_crit) counts only when it is at least
    :data:`BIAS_FLOOR` relative: below that it is float32 rounding of a near-zero-variance
    estimate (z is huge because the standard error is ~10⁻⁸), not a failure.
    """
    if nonfinite:
        return "breaks down", f"{nonfinite} NaN/Inf samples"
    if not math.isfinite(bias_z) and abs(rel_bias) > BIAS_FLOOR:
        return "breaks down", "silent: wrong estimate with zero reported stderr (no sample hit)"
    if abs(bias_z) > z_crit and abs(rel_bias) > BIAS_FLOOR:
        return "breaks down", (f"unexplained error: bias {rel_bias:+.2g} at |z| = {abs(bias_z):.3g} "
                               f"> {z_crit:.1f}")
    if not rel_rmse <= BREAKDOWN_REL_RMSE:
        return "breaks down", f"noise: rel RMSE {rel_rmse:.2g} > {BREAKDOWN_REL_RMSE:g}"
    return "ok", ""


def ratio_summary(rows: list[dict]) -> dict[str, dict[str, float]]:
    """Per comparison: median, quartiles and count of the A/B pair ratios."""
    out = {}
    for name, *_ in RATIO_COMPARISONS:
        sel = [x for x in rows if x["comparison"] == name]
        r = np.array([number(x, "ratio") for x in sel])
        if r.size:
            out[name] = {"median": float(np.median(r)), "q1": float(np.percentile(r, 25)),
                         "q3": float(np.percentile(r, 75)), "pairs": int(r.size),
                         "t_a": float(np.median([number(x, "t_a") for x in sel])),
                         "t_b": float(np.median([number(x, "t_b") for x in sel]))}
    return out


def efficiency_ratios(rows: list[dict], cost_rows: list[dict] | None = None) -> dict[str, dict[str, float]]:
    """Time to reach equal error, relative: (σ²·t per sample) of uniform over that of bsdf, per
    estimator problem, at the largest N (σ² = N·mean(stderr²); t = median of the interleaved
    cost rounds in cost.csv / N, else the row's steady time / N).

    For an unbiased estimator the error after time T is √(σ² t/T), so the time to reach a
    given error is proportional to σ²·t: the ratio is how much sooner BSDF sampling gets there.
    """
    out = {}
    per_sample: dict[tuple[str, str], list[float]] = {}
    for r in cost_rows or []:
        per_sample.setdefault((r["scene"], r["method"]), []).append(number(r, "seconds") / int(r["samples"]))
    med = {k: float(np.median(v)) for k, v in per_sample.items()}
    est = [r for r in rows if r["group"] == "estimator"]
    for scene in sorted({r["scene"] for r in est}):
        last: dict[str, dict] = {}
        for r in est:
            if r["scene"] == scene and (r["method"] not in last
                                        or int(r["samples"]) > int(last[r["method"]]["samples"])):
                last[r["method"]] = r
        cost = {m: number(r, "var_n") * med.get((scene, m), number(r, "wall_time_s") / int(r["samples"]))
                for m, r in last.items()}
        if "uniform" in cost and "bsdf" in cost and cost["bsdf"] > 0:
            out[scene] = {"uniform_over_bsdf": cost["uniform"] / cost["bsdf"],
                          "samples": int(last["bsdf"]["samples"]),
                          **{f"cost_{m}": c for m, c in cost.items()}}
    return out


def _mis_cells(stab: list[dict], method: str = "mis") -> tuple[list[tuple], dict[tuple[str, str], float]]:
    """(rt, rn, cell key, near-zero, rp) for every cell where ``method`` and both strategies ran,
    and the median time per estimate of each (light, method)."""
    cells: dict[tuple, dict[str, dict]] = {}
    for r in stab:
        cells.setdefault((r["light"], r["exponent"], r["theta_i"]), {})[r["method"]] = r
    # Cost per estimate hardly depends on p or θ_i: one median per (light, method) is far less
    # noisy than a single timed launch per cell on a shared machine.
    cost: dict[tuple[str, str], list[float]] = {}
    for r in stab:
        cost.setdefault((r["light"], r["method"]), []).append(number(r, "seconds"))
    t = {k: float(np.median(v)) for k, v in cost.items()}
    found = []
    for key, m in cells.items():
        if not all(k in m for k in (method, "bsdf", "light")):
            continue
        light = key[0]
        best = min(("bsdf", "light"), key=lambda k: number(m[k], "var_n") * t[(light, k)])
        if m[best]["verdict"] != "ok" or number(m[best], "var_n") <= 0:
            continue
        var_mis = number(m[method], "var_n")
        rt = math.sqrt(var_mis * t[(light, method)] / (number(m[best], "var_n") * t[(light, best)]))
        best_var = min(x for x in (number(m["bsdf"], "var_n"), number(m["light"], "var_n")) if x > 0)
        rn = math.sqrt(var_mis / best_var)
        # N pairs (2N samples) against N samples of the better strategy: var_pair = var_n / 2.
        rp = math.sqrt(var_mis / 2.0 / best_var) if method == "mis" else rn
        near_zero = math.sqrt(number(m[best], "var_n")) / number(m[best], "exact") < NEAR_ZERO_REL_SD
        found.append((rt, rn, key, near_zero, rp))
    return found, t


def mis_ratios(stab: list[dict], method: str = "mis") -> dict[str, Any]:
    """``method``'s error over the better of bsdf/light sampling, at equal time and at equal samples.

    Equal time: √(σ²_mis t_mis / min(σ²_b t_b, σ²_l t_l)); equal samples: √(σ²_mis / min(σ²_b, σ²_l)),
    σ² the per-sample-equivalent variance N·mean(stderr²).  Stability cells where the better
    strategy itself breaks down (its variance estimate cannot be trusted) are left out.
    "Near-zero-variance" cells, where the better strategy's relative per-sample standard
    deviation is below :data:`NEAR_ZERO_REL_SD`, are reported apart: Veach's bound on MIS
    (balance/power heuristic variance ≤ best variance + (1/min nᵢ − 1/Σnᵢ) μ²) is additive in
    μ², so against an almost zero-variance strategy no fixed split can stay within a factor.
    """
    found, t = _mis_cells(stab, method)

    def worst(sel, idx):
        return max(sel, key=lambda x: x[idx]) if sel else (math.nan, math.nan, None, False, math.nan)

    regular = [x for x in found if not x[3]]
    wt, wn, wr, wp = worst(found, 0), worst(found, 1), worst(regular, 0), worst(regular, 4)
    return {"pairs_regular_max": wp[4], "pairs_regular_cell": wp[2],
            "time_per_estimate": {f"{k[0]}/{k[1]}": v for k, v in t.items()},
            "equal_time_max": wt[0], "equal_time_cell": wt[2],
            "equal_samples_max": wn[1], "equal_samples_cell": wn[2],
            "regular_time_max": wr[0], "regular_time_cell": wr[2],
            "equal_time_median": float(np.median([x[0] for x in found])) if found else float("nan"),
            "equal_samples_median": float(np.median([x[1] for x in found])) if found else float("nan"),
            "within_1_2": sum(x[0] <= 1.2 for x in found), "cells": len(found),
            "within_1_2_samples": sum(x[1] <= 1.2 for x in found),
            "near_zero_cells": len(found) - len(regular)}


def mis_cell_table(stab: list[dict], method: str = "mis_optimal", baseline: str = "mis") -> list[dict]:
    """Per stability cell: ``method`` and ``baseline`` over the better single strategy, at equal
    time (rt) and equal samples (rn), and ``method`` over ``baseline`` at equal time."""
    ours = {x[2]: x for x in _mis_cells(stab, method)[0]}
    base = {x[2]: x for x in _mis_cells(stab, baseline)[0]}
    rows = []
    for key in sorted(ours, key=lambda k: (k[0], float(k[1]), float(k[2]))):
        o, b = ours[key], base.get(key)
        rows.append(dict(light=key[0], exponent=float(key[1]), theta_i=float(key[2]),
                         near_zero=o[3], rt=o[0], rn=o[1],
                         rt_base=b[0] if b else math.nan, rn_base=b[1] if b else math.nan,
                         vs_base=o[0] / b[0] if b and b[0] > 0 else math.nan))
    return rows


def loglog_slope(rows: list[dict], group: str, scene: str, method: str, variant: str = "llvm_ad_rgb",
                 min_samples: int = 1) -> float:
    """OLS slope of log RMSE on log samples of one curve (NaN with fewer than 3 points)."""
    pts = [(int(r["samples"]), number(r, "rmse")) for r in rows
           if r["group"] == group and r["scene"] == scene and r["method"] == method
           and r["variant"] == variant and int(r["samples"]) >= min_samples and number(r, "rmse") > 0]
    if len(pts) < 3:
        return float("nan")
    n, e = zip(*sorted(pts))
    return float(np.polyfit(np.log(n), np.log(e), 1)[0])
