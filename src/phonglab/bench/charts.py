"""The bench's charts (matplotlib, Agg backend): error against time, and the stability map.

* :func:`chart_error_time` — error against steady-state time on log-log axes, one curve per
  method (labelled with the sample count at its last point), the Pareto front
  (:func:`phonglab.bench.analysis.pareto_front`) dashed: ``estimators.png`` (one panel per
  estimator problem, relative RMSE), ``renders.png`` and ``variants.png`` (RMSE against the
  reference).
* :func:`chart_stability` — ``stability.png``: per estimator (columns) and light (rows), log10
  of the relative RMSE over exponent × θ_i, a red ✗ where the verdict is "breaks down".
* :func:`chart_mis` — ``mis.png``: per light (rows), the error of power-heuristic ``mis`` and
  of ``mis_optimal`` over the better single strategy at equal time, and of ``mis_optimal`` at
  equal samples (:func:`phonglab.bench.analysis.mis_cell_table`), per exponent × θ_i.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..physics.estimators import METHODS
from .analysis import mis_cell_table, pareto_front
from .config import BREAKDOWN_REL_RMSE, STABILITY_ANGLES, STABILITY_EXPONENTS, STABILITY_LIGHTS, STABILITY_N
from .csvlog import number, open_log


def _plt():
    """matplotlib.pyplot on the Agg backend (imported here: it costs ~0.5 s of start-up)."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def _error_time_axes(ax, curves: dict[str, list[tuple[float, float, int]]], title: str,
                     ylabel: str, xlabel: str = "steady-state wall time per estimate [s]") -> None:
    allpts = []
    for label, pts in curves.items():
        pts = sorted(p for p in pts if math.isfinite(p[0]) and math.isfinite(p[1]) and p[1] > 0)
        if not pts:
            continue
        t, e, n = zip(*pts)
        ax.plot(t, e, "o-", ms=3.5, lw=1.2, label=label)
        ax.annotate(f"{n[-1]}", (t[-1], e[-1]), fontsize=6, xytext=(3, 0),
                    textcoords="offset points")
        allpts += [(a, b) for a, b, _ in pts]
    front = pareto_front(allpts)
    if front:
        ft, fe = zip(*front)
        ax.step(ft, fe, where="post", color="k", lw=0.8, ls="--", alpha=0.7, label="Pareto front")
        ax.plot(ft, fe, "o", mfc="none", mec="k", ms=7, mew=1.0)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=9)
    ax.grid(True, which="both", alpha=0.25)
    ax.legend(fontsize=7)


def chart_error_time(out: Path, figdir: Path) -> list[Path]:
    """error-vs-time PNGs: estimators (one panel per problem), renders, variants."""
    plt = _plt()
    rows = open_log(out, "results").rows
    written = []
    groups = [("estimator", "estimators.png", "relative RMSE", True),
              ("render", "renders.png", "RMSE vs reference", False),
              ("variant", "variants.png", "RMSE vs reference", False)]
    for group, name, ylabel, relative in groups:
        sel = [r for r in rows if r["group"] == group]
        if not sel:
            continue
        scenes = sorted({r["scene"] for r in sel})
        fig, axes = plt.subplots(1, len(scenes), figsize=(5.2 * len(scenes), 4.2), squeeze=False)
        for ax, scene in zip(axes[0], scenes):
            curves: dict[str, list] = {}
            for r in sel:
                if r["scene"] != scene:
                    continue
                err = number(r, "rmse") / (number(r, "reference") if relative else 1.0)
                label = r["method"] if group != "variant" else f"{r['method']} {r['variant']}"
                curves.setdefault(label, []).append((number(r, "wall_time_s"), err, int(r["samples"])))
            _error_time_axes(ax, curves, scene, ylabel,
                             "steady-state wall time per estimate [s]" if group == "estimator"
                             else "steady-state wall time per render [s] (median of repeats)")
        fig.suptitle({"estimator": "Reflection-equation estimators: error against time "
                                   "(labels: N at the last point)",
                      "render": "Cornell box 32 px renders: error against time (labels: spp)",
                      "variant": "llvm_ad_rgb vs scalar_rgb, Cornell box 16 px (labels: spp)"}[group],
                     fontsize=10)
        fig.tight_layout()
        path = figdir / name
        fig.savefig(path, dpi=110)
        plt.close(fig)
        written.append(path)
    return written


def _stability_grid_axes(ax, title: str, bottom: bool, left: bool) -> None:
    """Ticks, title and (on the bottom row, the left column) labels of one panel of the
    stability grid (θ_i rows, exponent columns), as the stability and MIS charts draw it."""
    ax.set_xticks(range(len(STABILITY_EXPONENTS)),
                  [f"{p:g}" for p in STABILITY_EXPONENTS], fontsize=6, rotation=45)
    ax.set_yticks(range(len(STABILITY_ANGLES)), [f"{t:g}" for t in STABILITY_ANGLES], fontsize=6)
    ax.set_title(title, fontsize=8)
    if bottom:
        ax.set_xlabel("exponent p", fontsize=7)
    if left:
        ax.set_ylabel("θ_i [deg]", fontsize=7)


def chart_stability(out: Path, figdir: Path) -> Path | None:
    """Heatmap per estimator (columns) and light (rows): log10 relative RMSE, ✗ = breaks down."""
    plt = _plt()
    rows = open_log(out, "stability").rows
    if not rows:
        return None
    lights = list(STABILITY_LIGHTS)
    fig, axes = plt.subplots(len(lights), len(METHODS), figsize=(3.1 * len(METHODS), 2.9 * len(lights)),
                             squeeze=False)
    im = None
    for i, light in enumerate(lights):
        for j, method in enumerate(METHODS):
            ax = axes[i][j]
            grid = np.full((len(STABILITY_ANGLES), len(STABILITY_EXPONENTS)), np.nan)
            bad = np.zeros_like(grid, dtype=bool)
            for r in rows:
                if r["light"] != light or r["method"] != method:
                    continue
                a = STABILITY_ANGLES.index(float(r["theta_i"]))
                p = STABILITY_EXPONENTS.index(float(r["exponent"]))
                v = number(r, "rel_rmse")
                grid[a, p] = math.log10(v) if v > 0 else -7.0
                bad[a, p] = r["verdict"] != "ok"
            im = ax.imshow(np.clip(grid, -5, 1), origin="lower", cmap="viridis", vmin=-5, vmax=1,
                           aspect="auto")
            for a in range(grid.shape[0]):
                for p in range(grid.shape[1]):
                    if bad[a, p]:
                        ax.text(p, a, "✗", ha="center", va="center", color="red", fontsize=10,
                                fontweight="bold")
            _stability_grid_axes(ax, f"{method} — {light}", i == len(lights) - 1, j == 0)
    fig.subplots_adjust(hspace=0.45, wspace=0.3)
    fig.colorbar(im, ax=axes, shrink=0.8, label="log10 relative RMSE (N = 2^14)")
    fig.suptitle(f"Stability map: pure-specular phong, N = {STABILITY_N} samples; "
                 f"✗ = breaks down (rel. RMSE > {BREAKDOWN_REL_RMSE:g}, NaN/Inf, or unexplained error)",
                 fontsize=9)
    path = figdir / "stability.png"
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return path


def chart_mis(out: Path, figdir: Path) -> Path | None:
    """Heatmaps of MIS over the better of BSDF/light sampling: log2 of the error ratio, the
    value written in each cell, a box where the better strategy is near-zero-variance."""
    plt = _plt()
    table = mis_cell_table(open_log(out, "stability").rows)
    if not table:
        return None
    lights = list(STABILITY_LIGHTS)
    panels = (("rt_base", "mis (power), equal time"), ("rt", "mis_optimal, equal time"),
              ("rn", "mis_optimal, equal samples"))
    fig, axes = plt.subplots(len(lights), len(panels), figsize=(4.2 * len(panels), 3.2 * len(lights)),
                             squeeze=False)
    im = None
    for i, light in enumerate(lights):
        for j, (key, title) in enumerate(panels):
            ax = axes[i][j]
            grid = np.full((len(STABILITY_ANGLES), len(STABILITY_EXPONENTS)), np.nan)
            for c in table:
                if c["light"] != light:
                    continue
                a = STABILITY_ANGLES.index(c["theta_i"])
                p = STABILITY_EXPONENTS.index(c["exponent"])
                grid[a, p] = c[key]
                ax.text(p, a, f"{c[key]:.2f}" if c[key] < 10 else f"{c[key]:.2g}", ha="center", va="center", fontsize=5.5,
                        color="white" if abs(math.log2(max(c[key], 1e-9))) > 1.5 else "black",
                        fontweight="bold" if c["near_zero"] else "normal")
            im = ax.imshow(np.log2(np.clip(grid, 0.25, 4.0)), origin="lower", cmap="coolwarm",
                           vmin=-2, vmax=2, aspect="auto")
            _stability_grid_axes(ax, f"{title} — {light}", i == len(lights) - 1, j == 0)
    fig.subplots_adjust(hspace=0.45, wspace=0.3)
    fig.colorbar(im, ax=axes, shrink=0.8, label="log2 (MIS error / better single strategy's)")
    fig.suptitle("MIS against the better of BSDF and light sampling (target ≤ 1.2); bold: the "
                 "better strategy is near-zero-variance; blank: it breaks down", fontsize=9)
    path = figdir / "mis.png"
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return path
