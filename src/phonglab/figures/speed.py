r"""Notebook 04 (speed against accuracy): estimator convergence, efficiency, the planner's depths.

:func:`convergence_curves` + :func:`fig_convergence`, :func:`efficiency_table`,
:func:`fig_plan_depths`.  The estimators are :mod:`phonglab.physics.estimators`'s (their
variance and cost measured here, N = 2^k samples, S seeds); efficiency is 1/(σ² t)
[E. Veach, *Robust Monte Carlo Methods for Light Transport Simulation*, 1997, §2.4.3].  The
stability map and the render charts come from :mod:`phonglab.bench`, the plan from
:mod:`phonglab.planner`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

import numpy as np

from ..physics import estimators
from ..planner import BIAS_FRACTION
from .common import figure


@dataclass
class ConvergenceCurves:
    """RMSE of each estimator against N (S seeds), with its prediction σ/√N."""

    problem_label: str
    exact: float
    n: np.ndarray                                    #: sample counts
    rmse: dict[str, np.ndarray] = field(default_factory=dict)       #: relative RMSE per method
    predicted: dict[str, np.ndarray] = field(default_factory=dict)  #: σ/(μ√N) per method
    #: time of one N-sample estimate: N × the per-sample cost measured at the largest N
    #: (small launches are dominated by a fixed ~0.05 ms overhead that says nothing of the method)
    seconds: dict[str, np.ndarray] = field(default_factory=dict)
    slope: dict[str, float] = field(default_factory=dict)           #: fitted log-log slope


def convergence_curves(problem: estimators.Problem | None = None,
                       methods: Sequence[str] = estimators.METHODS,
                       exponents: Sequence[int] = tuple(range(8, 17, 2)), seeds: int = 16,
                       seed: int = 1) -> ConvergenceCurves:
    """Relative RMSE against N = 2^k for the reflection-equation estimators of
    :mod:`phonglab.physics.estimators` (S seeds per N), the RMSE the per-sample variance predicts,
    the time of one estimate (N × the per-sample cost of the largest launch), and the fitted
    log-log slope (−½ for Monte Carlo)."""
    problem = problem or estimators.Problem(diffuse_reflectance=0.2, specular_reflectance=0.7,
                                            exponent=100.0, theta_i=30.0, light="disk",
                                            half_angle=5.0)
    est = estimators.ReflectionEstimators(problem)
    exact = est.exact()
    ns = np.array([2 ** k for k in exponents])
    out = ConvergenceCurves(problem.label, exact, ns)
    for m in methods:
        _, var, _ = est.moments(m, n=1 << 18)
        rmse, times = [], []
        for n in ns:
            e = est.run(m, int(n), seed=seed, batches=seeds)
            rmse.append(float(np.sqrt(np.mean((e.values - exact) ** 2))) / abs(exact))
            times.append(e.seconds / seeds)
        out.rmse[m] = np.array(rmse)
        per = ns / 2 if m == "mis" else ns
        out.predicted[m] = np.sqrt(var / per) / abs(exact)
        out.seconds[m] = ns * (times[-1] / ns[-1])
        good = out.rmse[m] > 0
        out.slope[m] = float(np.polyfit(np.log(ns[good]), np.log(out.rmse[m][good]), 1)[0]) \
            if good.sum() >= 2 else float("nan")
    return out


def fig_convergence(curves: ConvergenceCurves):
    """Left: relative RMSE against N (points) and σ/√N (lines). Right: RMSE against time."""
    fig = figure(10.0, 4.0)
    ax1, ax2 = fig.subplots(1, 2)
    for k, m in enumerate(curves.rmse):
        color = f"C{k}"
        ax1.loglog(curves.n, curves.rmse[m], "o", color=color,
                   label=f"{m} (slope {curves.slope[m]:.2f})")
        ax1.loglog(curves.n, curves.predicted[m], "-", color=color, alpha=0.6)
        ax2.loglog(curves.seconds[m] * 1e3, curves.rmse[m], "o-", color=color, label=m)
    ax1.set_xlabel("samples N")
    ax1.set_ylabel("relative RMSE")
    ax1.set_title("error falls as N^-1/2 (lines: σ/√N)")
    ax1.legend(fontsize=8)
    ax2.set_xlabel("time per estimate [ms] (N × per-sample cost)")
    ax2.set_ylabel("relative RMSE")
    ax2.set_title("error against time: lower-left wins")
    fig.suptitle(curves.problem_label, fontsize=9)
    return fig


def efficiency_table(curves: ConvergenceCurves) -> list[tuple[str, float, float]]:
    """(method, σ² per sample relative, time-to-equal-error relative to the best method):
    efficiency 1/(σ² t) [Veach 1997, §2.4.3], from the largest N of :func:`convergence_curves`."""
    cost = {m: (curves.rmse[m][-1] ** 2) * curves.seconds[m][-1] for m in curves.rmse}
    best = min(c for c in cost.values() if c > 0) if any(c > 0 for c in cost.values()) else 1.0
    return [(m, float(curves.rmse[m][-1]), float(cost[m] / best)) for m in curves.rmse]


def fig_plan_depths(plan):
    """The planner's depth evidence: relative RMS of the omitted deeper bounces b(d) for each
    pilot depth, the budget 0.25·E it must stay under, and the chosen depth."""
    depths = [d for d in plan.pilot.depths if d.depth != -1]
    fig = figure(5.5, 3.2)
    ax = fig.subplots()
    x = [d.depth for d in depths]
    y = [max(d.bias, 1e-6) for d in depths]
    ax.semilogy(x, y, "o-", label="omitted deeper bounces b(d) (relative RMS)")
    ax.axhline(BIAS_FRACTION * plan.target_error, color="C3", ls="--",
               label=f"budget {BIAS_FRACTION:g} × target error")
    if plan.max_depth != -1:
        ax.axvline(plan.max_depth, color="C2", ls=":", label=f"chosen max_depth {plan.max_depth}")
    ax.set_xlabel("max_depth")
    ax.set_ylabel("relative RMS (floored at 1e-6)")
    ax.set_title(f"{Path(plan.scene).name}: pilot at {plan.pilot.spp} spp", fontsize=9)
    ax.legend(fontsize=7)
    return fig
