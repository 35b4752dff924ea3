r"""The ``chi2`` and ``normalization`` topics: does ``sample`` draw directions with the density
``eval_pdf`` reports, and does that density (and the value) integrate to 1 over the sphere?

``chi2``.  At each incidence of :data:`.lanes.INCIDENCES`, N directions from ``sample`` with
seeded uniforms, histogrammed in the (φ, cos θ) bins of ``mi.chi2.SphericalDomain``
(:class:`phonglab.validate.sphere_bins.Grid`, the BSDF topic's grid) in a frame turned so
that the forward direction −wi lies on the grid's equator, half a column off a column edge:
mi.chi2 bins about the world's pole, where a |g| ≥ 0.9 lobe aimed at the pole would fall into
the thin wedges of the first row.  Expected counts N·∫pdf per bin from the BSDF topic's
lobe-adaptive Gauss-Legendre quadrature with its stated error bound
(:func:`~phonglab.validate.sphere_bins.expected_counts`, re-integrating bins that
contradict their count by > 4σ, :func:`~phonglab.validate.sphere_bins.recheck`), Pearson's
χ² with Mitsuba's pooling (:func:`phonglab.stats.pearson_chi2`).  The test is of the density's
shape: expected counts are scaled to the samples counted (the scale is ``normalization``'s), as
the BSDF topic does.  Each incidence is one test at the Šidák level ``stats.sidak(ALPHA, m)``,
m the phase function's statistical tests (the incidences), so a correct phase function fails
by chance with probability ALPHA = 0.01.  A sample counts when wo and the weight are finite
and the weight is not 0; a cell whose samples are all non-finite is not tested (the
``finite`` topic's).

``normalization``.  ∫ pdf dω and ∫ value dω (each channel) over the sphere, at each incidence,
by a deterministic tensor Gauss-Legendre rule in (μ, φ) about the forward direction −wi: μ
panels graded geometrically towards μ = ±1 (down to 10⁻⁸ of the end: a g = 0.99 lobe has
width (1 − g)²/2g ≈ 5·10⁻⁵ in μ) plus 32 uniform ones (a tabulated function's nodes at
multiples of 1/16 of [−1, 1] are panel edges for tables of 2^k + 1 values), 16 uniform φ
panels.  The rule is run with k and 2k nodes per panel and axis; the error bound of the finer
result is |Q_2k − Q_k| (Gauss-Legendre converges geometrically on an analytic integrand, so the
finer rule is far better than the difference), and the tolerance is
4 |Q_2k − Q_k| + :data:`FLOAT32_FLOOR` (10⁻⁴: a sum of float32 pdf values, each good to a few
10⁻⁷, carried in float64).  Value: Mitsuba's phase functions are normalized (value = pdf for
all built-ins; the albedo is the medium's, src/render/medium.cpp), so ∫ value dω = 1 too.
"""

from __future__ import annotations

import math

import numpy as np

from ... import stats
from .. import sphere_bins
from . import lanes
from .config import rng
from .topics import Row

#: Round-off floor of a quadrature of float32 pdf values (see the module docstring).
FLOAT32_FLOOR = 1e-4


def grid_frame(wi: np.ndarray, grid: sphere_bins.Grid) -> np.ndarray:
    """Rows of the histogram frame at incidence wi: −wi at φ = π/cols on the equator."""
    s, t, n = lanes.basis(-np.asarray(wi, np.float64))
    a = math.pi / grid.cols
    return np.stack([math.cos(a) * n - math.sin(a) * s, math.sin(a) * n + math.cos(a) * s, t])


def chi2_cell(phase, wi: np.ndarray, opts, level: float, r: np.random.Generator) -> dict:
    grid, n = sphere_bins.Grid(opts.chi2_res), opts.chi2_samples
    frame = grid_frame(wi, grid)
    wis = np.tile(wi, (n, 1))
    wo, w, p = lanes.sample(phase, wis, r.random(n), r.random((n, 2)))
    finite = np.all(np.isfinite(wo), axis=1) & np.all(np.isfinite(w), axis=1)
    kept = finite & np.any(w != 0, axis=1)
    local = wo[kept] @ frame.T

    def pdf_fn(d):
        return lanes.pdf(phase, np.broadcast_to(wi, (len(d), 3)), d @ frame)

    rec = {"wi": np.asarray(wi).tolist(), "nonfinite_samples": int((~finite).sum())}
    if not kept.any():
        return {**rec, "status": "nonfinite" if not finite.any() else "empty"}
    expected, integration = sphere_bins.expected_counts(grid, pdf_fn, n, opts.chi2_ires,
                                                        opts.chi2_ires_max)
    index = grid.index(local)
    hist = grid.histogram(local, index)
    expected = sphere_bins.recheck(grid, pdf_fn, n, expected, local, opts.chi2_ires_max,
                                   integration, index)
    pdf_sum = float(expected.sum()) / n
    scale = float(kept.sum()) / (pdf_sum * n) if pdf_sum > 0 else 1.0
    test = stats.pearson_chi2(hist, expected * scale)
    problems = [m for m, bad in (
        ("a bin has a negative expected count (pdf < 0)", bool((expected < 0).any())),
        (f"{test.impossible} samples lie in bins of expected count 0", test.impossible > 0),
        ("fewer than 2 bins to compare (dof < 1)", test.dof < 1)) if bad]
    ok = not problems and test.p_value >= level
    rec.update(p_value=test.p_value, statistic=test.statistic, dof=test.dof,
               hist_sum=float(kept.sum()) / n, pdf_sum=pdf_sum, scale=scale,
               status="pass" if ok else "fail", problems=problems, integration=integration)
    if not ok:
        flat = int(np.nanargmax(np.abs(np.nan_to_num(test.residual, nan=0.0))))
        rec["worst_bin"] = {**grid.ranges(flat), "observed": float(hist.ravel()[flat]),
                            "expected": float((expected * scale).ravel()[flat])}
    return rec


def chi2(phase, opts, m_tests: int) -> list[Row]:
    level = stats.sidak(stats.ALPHA, m_tests)
    r = rng(opts.seed, "chi2")
    records = [chi2_cell(phase, wi, opts, level, r) for wi in lanes.INCIDENCES]
    tested = [c for c in records if c["status"] in ("pass", "fail")]
    failed = [c for c in tested if c["status"] == "fail"]
    grid = sphere_bins.Grid(opts.chi2_res)
    if not tested:
        return [Row("chi2", "sampling matches eval_pdf (min p-value)", None, None, None, None,
                    "skipped", "no incidence has a finite sample with a non-zero weight (the "
                    "finite topic's)", {"cells": records})]
    p_min = min(c["p_value"] for c in tested)
    reason = (f"Pearson χ² of sample() vs eval_pdf's pdf (stats.pearson_chi2, "
              f"{opts.chi2_samples} samples, {grid.rows} cos θ x {grid.cols} φ bins about an "
              f"axis across the forward direction, pdf integrated per bin to "
              f"{sphere_bins.EPS:g} of its Poisson error, counts scaled to the samples kept) at "
              f"{len(tested)} incidences, each at the Šidák level {level:.2e} of the phase "
              f"function's {m_tests} statistical tests")
    if failed:
        reason += "; rejected at wi = " + ", ".join(
            "(" + ", ".join(f"{x:.2f}" for x in c["wi"]) + ")" for c in failed)
    skipped = len(records) - len(tested)
    if skipped:
        reason += f"; {skipped} incidences with no finite sample not tested (the finite topic's)"
    row = Row("chi2", "sampling matches eval_pdf (min p-value)", p_min, level, None, level,
              "fail" if failed else "pass", reason, {"cells": records, "level": level})
    row.failing_lanes = {"cell": failed} if failed else None
    return [row]


def _mu_edges() -> np.ndarray:
    d = 10.0 ** np.arange(-8.0, 0.01, 0.5)
    return np.unique(np.concatenate([-1.0 + d, 1.0 - d, np.linspace(-1.0, 1.0, 33)]))


def sphere_integrals(phase, wi: np.ndarray, k: int) -> tuple[float, np.ndarray]:
    """(∫ pdf dω, ∫ value dω per channel) at incidence wi, k Gauss-Legendre nodes per panel
    and axis (see the module docstring)."""
    t, wt = np.polynomial.legendre.leggauss(k)
    me = _mu_edges()
    pe = np.linspace(0.0, 2.0 * math.pi, 17)
    mu = (0.5 * (me[:-1] + me[1:])[:, None] + 0.5 * np.diff(me)[:, None] * t).ravel()
    wm = (0.5 * np.diff(me)[:, None] * wt).ravel()
    phi = (0.5 * (pe[:-1] + pe[1:])[:, None] + 0.5 * np.diff(pe)[:, None] * t).ravel()
    wp = (0.5 * np.diff(pe)[:, None] * wt).ravel()
    M, P = np.meshgrid(mu, phi, indexing="ij")
    W = np.outer(wm, wp).ravel()
    s = np.sqrt(np.maximum(0.0, 1.0 - M * M)).ravel()
    sb, tb, nb = lanes.basis(-np.asarray(wi, np.float64))
    d = (s * np.cos(P.ravel()))[:, None] * sb + (s * np.sin(P.ravel()))[:, None] * tb \
        + M.ravel()[:, None] * nb
    pdf_sum, val_sum = 0.0, 0.0
    chunk = 1 << 20
    for a in range(0, len(d), chunk):
        v, p = lanes.eval_pdf(phase, np.tile(wi, (len(d[a:a + chunk]), 1)), d[a:a + chunk])
        pdf_sum += float(np.sum(p * W[a:a + chunk]))
        val_sum = val_sum + np.sum(v * W[a:a + chunk, None], axis=0)
    return pdf_sum, np.atleast_1d(val_sum)


def normalization(phase, opts) -> list[Row]:
    k = opts.norm_nodes
    recs = []
    for wi in lanes.INCIDENCES:
        p1, v1 = sphere_integrals(phase, wi, k)
        p2, v2 = sphere_integrals(phase, wi, 2 * k)
        recs.append({"wi": wi.tolist(), "pdf": p2, "pdf_error": abs(p2 - p1),
                     "value": v2.tolist(), "value_error": float(np.max(np.abs(v2 - v1)))})
    rows = []
    for what, key, name in (("pdf", "pdf", "∫ pdf dω = 1 over the sphere"),
                            ("value", "value", "∫ value dω = 1 over the sphere")):
        dev = [float(np.max(np.abs(np.asarray(r[key]) - 1.0))) for r in recs]
        tol = [4.0 * r[f"{key}_error"] + FLOAT32_FLOOR for r in recs]
        excess = [d / t if np.isfinite(d) else math.inf for d, t in zip(dev, tol)]
        worst = int(np.argmax(excess))
        ok = all(e <= 1.0 for e in excess)
        row = Row("normalization", name, recs[worst][key] if key == "pdf" else
                  float(np.asarray(recs[worst][key])[np.argmax(np.abs(
                      np.asarray(recs[worst][key]) - 1.0))]), 1.0, None, tol[worst],
                  "pass" if ok else "fail",
                  f"∫ {what} dω at {len(recs)} incidences by a tensor Gauss-Legendre rule about "
                  f"the forward direction ({k} and {2 * k} nodes per panel, μ panels graded to "
                  f"±1); tolerance 4|Q_2k − Q_k| + {FLOAT32_FLOOR:g}; worst at wi = "
                  f"{np.round(recs[worst]['wi'], 3).tolist()}", {"incidences": recs})
        if not ok:
            row.failing_lanes = {"wi": np.array([r["wi"] for r, e in zip(recs, excess)
                                                 if e > 1.0])}
        rows.append(row)
    return rows
