r"""The ``chi2`` topic: does ``sample`` draw directions with the density ``pdf`` reports?

Pearson's χ² test, phonglab's own (numpy/scipy, so it runs in every variant, scalar ones
included, where ``mi.chi2`` cannot: it names ``mi.ScalarBoundingBox2f`` and tabulates with
JIT arrays): N directions from ``probe.sample`` with seeded uniforms, histogrammed in the
(φ, cos θ) bins of ``mi.chi2.SphericalDomain``, against N·∫pdf per bin from a lobe-adaptive
quadrature (:mod:`.sphere_bins`, which states the integration error bound; bins whose count
contradicts their integral by > 4σ are integrated again at the finest level,
:func:`.sphere_bins.recheck`, which only makes them more accurate), cells of expected
count < 5 pooled as ``mitsuba::math::chi2`` pools them, p-value from the χ² distribution
(:func:`phonglab.stats.pearson_chi2`).  It tests the density's shape: the histogram against
N·∫pdf per bin times ``scale`` = (samples counted)/(N·∫pdf) (a multinomial given that total,
dof = bins − 1; the cell keeps N·∫pdf as ``expected``, the residual map and the worst bin are
against the scaled counts); the scale, ∫pdf against the fraction counted, is the ``normalization`` topic's, which
sees a pdf × 1.01 at once, where a histogram of 10⁶ samples sees it only sometimes (so a
planted scale defect failed χ² or not by the luck of the seed).  One test per incidence cell; each at the Šidák level
``stats.sidak(ALPHA, m)`` where m counts every statistical test of the BSDF (χ² cells and the
energy cells that use sample weights), so the BSDF as a whole fails by chance with probability
ALPHA = 0.01.

What counts as a sample (:func:`_kept`): weight ≠ 0 (a rejected sample has weight 0), or
weight 0 at a direction drawn inside the support where the BSDF is black
(:func:`.lanes.black_at_wo`: the ``normalization`` topic's rule, the same per sample), not a
delta lobe's (``pdf`` has no density for it: a mixture such as ``plastic`` is histogrammed on
its non-delta part only, whose ∫pdf is then < 1 in step with the histogram), a finite
direction.  Without the black-at-wo part, plastic at int_ior 1 (η = 0.99972 < 1) would fail:
its diffuse samples beyond the critical angle (cos θ_o < 0.0236, 0.056 % of them) have eval
0 -- the coating reflects that light back in -- so their weight is 0, and the histogram's
first row would be empty against pdf's cos θ_o share there (p = 3.5e-13 at default sizes).

A cell is rejected, as ``mi.chi2`` rejects it, when samples fall in a bin of expected count
0, a bin's expected count is negative, ∫pdf > 1.1, or dof < 1 -- except a cell whose
samples and pdf both lie within one bin and agree there (``narrow``: a lobe narrower
than a bin, whose shape this grid cannot test, e.g. roughdielectric's transmission at η ≈ 1,
α·|1 − η|/η wide): it is not tested, and the reason says so.  A failing cell
keeps its histogram, its expected counts and its residual map (obs − scale·exp)/√(scale·exp) (NaN where the
bin was pooled or empty), and names its worst bin (θ_o/φ_o range, observed, expected,
residual), which the row's evidence line repeats for the cell of smallest p.

Guards: a cell whose histogram is empty while ∫pdf > 0 fails (``mi.chi2`` would accept an
empty histogram vacuously) -- unless the BSDF is black there (``eval`` 0 at every direction
``sample`` draws and at random ones: :func:`black_at`), where every weight is 0 and the
histogram is of the directions ``sample`` drew (``bs.pdf > 0``) instead; a cell where both
are empty (nothing sampled, zero pdf) is not tested.

Delta lobes cannot be histogrammed: for a BSDF whose every component is a delta lobe the
topic instead checks each sampled direction against the law of reflection (reflect(wi)) or
Snell's law with the sample's own η (transmission, wo = −wi for a null/thin interface),
to 1e-4 per component of the unit vector (float32 trigonometry is good to ~1e-6).
"""

from __future__ import annotations

import math

import numpy as np

from ... import probe, stats
from .. import sphere_bins
from . import lanes
from .topics import Row

#: Tolerance of a delta sample's direction, per vector component (see the module docstring).
DIRECTION_TOL = 1e-4


def _kept(bsdf, wi: np.ndarray, s: probe.Sample, black: bool) -> np.ndarray:
    """Which samples the histogram counts (N,) bool.

    A sample counts when its weight is not 0 (Mitsuba marks a rejected sample so) or is 0
    where the BSDF is black at its wo (:func:`.lanes.black_at_wo`), or, with ``black``,
    when ``sample`` drew a direction (``bs.pdf > 0``) inside the support (``pdf(wo) > 0``;
    a rejected one keeps its bs.pdf): a black BSDF's weights are all 0, yet it draws its
    directions from its density.  Delta samples never count (``pdf`` has no density for
    them), nor do non-finite directions (the ``finite`` topic's).
    """
    finite = lanes.every(np.isfinite(s.wo))
    if black:
        drawn = (s.pdf > 0) & finite
        if drawn.any():
            drawn[drawn] = probe.pdf(bsdf, wi, s.wo[drawn]) > 0
    else:
        drawn = lanes.some(s.weight != 0) | lanes.black_at_wo(bsdf, wi, s)
    return drawn & finite & ~lanes.delta_mask(s.sampled_type)


def black_at(bsdf, wi: np.ndarray, opts) -> bool:
    """Whether ``eval`` is 0 at incidence wi for every direction sample() draws there and for
    random directions over the sphere (a black BSDF), from ``opts.n_finite`` lanes each."""
    r = lanes.rng(opts.seed, "chi2")
    n = opts.n_finite
    wis = np.repeat(np.asarray(wi, dtype=np.float64)[None], n, axis=0)
    s = probe.sample(bsdf, wis, r.random(n), r.random((n, 2)))
    d = lanes.sphere(r, n)
    ok = lanes.every(np.isfinite(s.wo))
    return not (np.any(probe.eval(bsdf, wis[ok], s.wo[ok])) or np.any(probe.eval(bsdf, wis, d)))


def _draws(r: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(u1 (n,), u2 (n, 2)): uniform in [0, 1), also after rounding to float32."""
    u1, u2 = r.random(n), r.random((n, 2))
    return np.minimum(u1, lanes.ONE_MINUS), np.minimum(u2, lanes.ONE_MINUS)


def chi2_cell(bsdf, wi: np.ndarray, opts, level: float, r: np.random.Generator) -> dict:
    """One χ² test at incidence wi, its N samples drawn from ``r``; returns the cell's record.

    A histogram of non-zero weights that is empty while ∫pdf > 0 is tested again on the
    drawn directions when the BSDF is black there (:func:`black_at`); else the cell fails.
    """
    wi = np.asarray(wi, dtype=np.float64)
    grid, n = sphere_bins.Grid(opts.chi2_res), opts.chi2_samples
    s = probe.sample(bsdf, wi, *_draws(r, n))
    kept = _kept(bsdf, wi, s, black=False)

    def pdf_fn(wo):
        return probe.pdf(bsdf, wi, wo)

    expected, integration = sphere_bins.expected_counts(grid, pdf_fn, n, opts.chi2_ires,
                                                        opts.chi2_ires_max)
    pdf_sum = float(expected.sum()) / n
    black = (not lanes.some(s.weight != 0).any() and pdf_sum >= 1e-6
             and black_at(bsdf, wi, opts))
    if black:
        kept = _kept(bsdf, wi, s, black=True)
    if not kept.any() and pdf_sum < 1e-6:
        return {"wi": wi.tolist(), "status": "empty", "hist_sum": 0.0, "pdf_sum": pdf_sum,
                "integration": integration}
    if pdf_sum == 0 and integration["nonfinite_pdf_dropped"]:
        # no density to test against: the pdf is NaN/Inf wherever it is not 0 (the finite
        # topic's failure; plastic with both reflectances 0, plastic.cpp:206)
        return {"wi": wi.tolist(), "status": "nonfinite", "hist_sum": float(kept.mean()),
                "pdf_sum": pdf_sum, "integration": integration}
    wo = s.wo[kept]
    index = grid.index(wo)
    hist = grid.histogram(wo, index)
    expected = sphere_bins.recheck(grid, pdf_fn, n, expected, wo, opts.chi2_ires_max,
                                   integration, index)
    pdf_sum = float(expected.sum()) / n
    # the shape: N·∫pdf scaled to the counted samples (the scale is normalization's)
    scale = float(kept.sum()) / (pdf_sum * n) if pdf_sum > 0 else 1.0
    test = stats.pearson_chi2(hist, expected * scale)
    hist_sum = float(kept.sum()) / n
    problems = [m for m, bad in (
        ("the histogram is empty while the pdf integrates to > 0", not kept.any()),
        ("a bin has a negative expected count (pdf < 0)", bool((expected < 0).any())),
        (f"the pdf integrates to {pdf_sum:.4f} over the sphere, expected ≤ 1 (refused above "
         f"1.1)", pdf_sum > 1.1),
        (f"{test.impossible} samples lie in bins of expected count 0", test.impossible > 0),
        ("fewer than 2 bins to compare (dof < 1)", test.dof < 1)) if bad]
    ok = not problems and test.p_value >= level
    if problems == ["fewer than 2 bins to compare (dof < 1)"] and kept.any():
        # one bin holds every sample and the pdf's mass: nothing to compare at this grid
        # (their totals are the normalization topic's); impossible samples would be a problem
        return {"wi": wi.tolist(), "status": "narrow", "hist_sum": hist_sum,
                "pdf_sum": pdf_sum, "integration": integration}
    messages = [f"Pooled {test.pooled_in} low-valued cells into {test.pooled_out} cells",
                f"Histogram sum = {hist_sum:.6f}, PDF sum = {pdf_sum:.6f}",
                f"Chi^2 statistic = {test.statistic:.6g} (d.o.f = {test.dof})"] + problems
    messages.append(("Accepted" if ok else "Rejected") + f" the null hypothesis (p-value = "
                    f"{test.p_value:.6g}, significance level = {level:.6g})")
    cell = {"wi": wi.tolist(), "p_value": test.p_value, "statistic": test.statistic,
            "dof": test.dof, "hist_sum": hist_sum, "pdf_sum": pdf_sum, "scale": scale,
            "status": "pass" if ok else "fail", "messages": "\n".join(messages),
            "problems": problems,
            "nonfinite_wo_dropped": int((~lanes.every(np.isfinite(s.wo))).sum()),
            "integration": integration}
    if black:
        cell["black"] = True
    if not ok:
        cell.update(histogram=hist.tolist(), expected=expected.tolist(),
                    residual=test.residual.tolist(),
                    worst_bin=_worst_bin(grid, hist, expected * scale, test.residual))
    return cell


def _worst_bin(grid: sphere_bins.Grid, hist: np.ndarray, expected: np.ndarray,
               residual: np.ndarray) -> dict:
    """The bin that most contradicts the pdf: samples where the expected count is 0 first,
    else the largest |residual|, else (everything pooled) the largest |obs − exp|."""
    impossible = np.where(expected == 0, hist, 0.0)
    if impossible.any():
        flat = int(np.argmax(impossible))
    elif np.isfinite(residual).any():
        flat = int(np.nanargmax(np.abs(residual)))
    else:
        flat = int(np.argmax(np.abs(hist - expected)))
    h, e, r = (float(a.ravel()[flat]) for a in (hist, expected, residual))
    return {**grid.ranges(flat), "observed": h, "expected": e, "residual": r}


def why_rejected(cell: dict, level: float) -> str:
    """A rejected cell's reason in the quantities' own units: what the χ² test could not
    accept before its p-value (a pdf integrating to more than 1, samples where the pdf is 0),
    else its p-value below the level."""
    out = list(cell.get("problems", []))
    out.append(f"p = {cell['p_value']:.3g}, below the level {level:.3g}"
               if cell["p_value"] < level else f"p = {cell['p_value']:.3g} ≥ the level, "
               f"rejected for the above")
    return "; ".join(out)


def chi2(bsdf, opts, m_tests: int) -> list[Row]:
    if lanes.delta_only(bsdf):
        return [delta_directions(bsdf, opts)]
    level = stats.sidak(stats.ALPHA, m_tests)
    cells = opts.cells(opts.chi2_cos, opts.chi2_phi)
    records, r = [], lanes.rng(opts.seed, "chi2")     # one stream, cell after cell
    for theta, phi in cells:
        rec = chi2_cell(bsdf, probe.direction(theta, phi), opts, level, r)
        rec.update(theta_deg=math.degrees(theta), phi=phi)
        records.append(rec)
    tested = [r for r in records if r["status"] not in ("empty", "nonfinite", "narrow")]
    narrow = sum(r["status"] == "narrow" for r in records)
    failed = [r for r in tested if r["status"] == "fail"]
    p_min = min((r["p_value"] for r in tested), default=1.0)
    where = ", ".join(f"θ_i={r['theta_deg']:.1f}° φ={r['phi']:.2f} ({why_rejected(r, level)})"
                      for r in failed)
    grid = sphere_bins.Grid(opts.chi2_res)
    reason = (f"Pearson χ² of sample() vs pdf() (stats.pearson_chi2, {opts.chi2_samples} "
              f"samples, {grid.rows} cos θ_o x {grid.cols} φ_o bins, pdf integrated per bin "
              f"to {sphere_bins.EPS:g} of its Poisson error) at {len(tested)} incidence cells, "
              f"each at the Šidák level {level:.2e} of the BSDF's {m_tests} statistical tests; "
              f"delta samples excluded") + (f"; rejected at {where}" if failed else "")
    untestable = sum(r["status"] == "nonfinite" for r in records)
    if untestable and tested:
        reason += (f"; {untestable} cells not tested: the pdf is not finite wherever it is "
                   f"not 0 there (the finite topic's)")
    if narrow and tested:
        reason += (f"; {narrow} cells not tested: every sample and the pdf's whole mass lie in "
                   f"one bin there (a lobe narrower than a bin: no shape to compare)")
    if not tested:
        nonfinite = sum(r["integration"]["nonfinite_pdf_dropped"] for r in records)
        if narrow:
            why = (f"at {narrow} incidence cells every sample and the pdf's whole mass lie in "
                   f"one bin (a lobe narrower than a bin: no shape to compare); the others "
                   f"sampled nothing")
        elif any(r["status"] == "nonfinite" for r in records):
            why = (f"the pdf is not finite wherever it is not 0 at every tested incidence "
                   f"({nonfinite} quadrature nodes; the finite topic's failure), so there is no "
                   f"density to test the samples against")
        else:
            why = ("the BSDF sampled nothing and has zero pdf at every tested incidence" +
                   (f" where its pdf is finite: it is not finite at {nonfinite} quadrature "
                    f"nodes (the finite topic's; dropped here)" if nonfinite else ""))
        return [Row("chi2", "sampling matches pdf", None, None, None, None, "skipped", why,
                    {"cells": records, "nonfinite_pdf_dropped": nonfinite})]
    details = {"cells": records, "level": level}
    if failed:
        worst = min(failed, key=lambda r: r["p_value"])
        details["worst_bin"] = {"theta_i_deg": worst["theta_deg"], "phi_i": worst["phi"],
                                "p_value": worst["p_value"], **worst["worst_bin"]}
    row = Row("chi2", "sampling matches pdf (min p-value)", p_min, level, None, level,
              "fail" if failed else "pass", reason, details)
    row.failing_lanes = {"cell": failed} if failed else None
    return [row]


def delta_directions(bsdf, opts) -> Row:
    """Delta-only BSDF: every sampled wo obeys reflection or Snell's law with bs.eta."""
    wi, _ = lanes.incident(opts.cells(), opts.n_identity)
    wi = wi[wi[:, 2] > 0]
    s = probe.sample_random(bsdf, wi, len(wi), seed=lanes.STREAMS.int_seed(opts.seed, "chi2"))
    live = lanes.some(s.weight != 0) & lanes.every(np.isfinite(s.wo))
    wi, wo, eta = wi[live], s.wo[live], s.eta[live]
    reflect = wo[:, 2] * wi[:, 2] > 0
    expected = np.empty_like(wo)
    expected[reflect] = wi[reflect] * np.array([-1.0, -1.0, 1.0])
    t = ~reflect
    e = np.where(eta[t] > 0, eta[t], 1.0)
    xy = -wi[t, :2] / e[:, None]
    z = -np.sign(wi[t, 2]) * np.sqrt(np.maximum(0.0, 1.0 - np.sum(xy * xy, axis=1)))
    expected[t] = np.column_stack([xy, z])
    err = np.max(np.abs(wo - expected), axis=1) if len(wo) else np.zeros(0)
    worst = float(err.max()) if err.size else 0.0
    return Row("chi2", "delta lobes: directions obey reflection/Snell", worst, 0.0, None,
               DIRECTION_TOL, "pass" if worst <= DIRECTION_TOL else "fail",
               f"delta lobes cannot be histogrammed: max |wo − expected| over {len(wo)} samples "
               f"({int(reflect.sum())} reflected, {int(t.sum())} transmitted) against "
               f"reflect(wi) / Snell with bs.eta; tolerance {DIRECTION_TOL:g} (float32 "
               f"trigonometry)", {"samples": int(len(wo))})
