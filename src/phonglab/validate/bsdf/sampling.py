r"""The ``chi2`` topic: does ``sample`` draw directions with the density ``pdf`` reports?

Pearson's χ² test of Mitsuba (``mi.chi2.ChiSquareTest`` over ``mi.chi2.SphericalDomain``):
the histogram of N sampled directions against N·∫pdf per cell, cells with expected count < 5
pooled, p-value from the χ² distribution.  One test per incidence cell; each at the Šidák level
``stats.sidak(ALPHA, m)`` where m counts every statistical test of the BSDF (χ² cells and the
energy cells that use sample weights), so the BSDF as a whole fails by chance with probability
ALPHA = 0.01.

Differences from ``mi.chi2.BSDFAdapter``: the BSDF is the given object (not re-loaded from a
type name), ``wi`` is a kernel input array (one compiled kernel for all cells), and samples
of a delta lobe get weight 0 -- ``pdf`` has no density for them; a mixture such as ``plastic``
is histogrammed on its non-delta part only, whose ∫pdf is then < 1 in step with the histogram.

Guards: a cell whose histogram is empty while ∫pdf > 0 fails (``mi.chi2`` would accept an
empty histogram vacuously) -- unless the BSDF is black there (``eval`` 0 at every direction
``sample`` draws and at random ones: :func:`black_at`), where every weight is 0 and the
histogram is of the directions ``sample`` drew (``bs.pdf > 0``) instead; a cell where both
are empty (nothing sampled, zero pdf) is not tested.  ``mi.chi2`` writes ``chi2_data.py`` into the working directory on failure
only when not ``quiet`` (mitsuba/python/chi2.py, ``run``: ``if not quiet: ... _dump_tables()``);
the test runs quietly, so it writes nothing and the process's directory is left alone.

Delta lobes cannot be histogrammed: for a BSDF whose every component is a delta lobe the
topic instead checks each sampled direction against the law of reflection (reflect(wi)) or
Snell's law with the sample's own η (transmission, wo = −wi for a null/thin interface),
to 1e-4 per component of the unit vector (float32 trigonometry is good to ~1e-6).
"""

from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi
import numpy as np

from ... import probe, stats
from . import lanes
from .topics import Row

#: Tolerance of a delta sample's direction, per vector component (see the module docstring).
DIRECTION_TOL = 1e-4


def _adapters(bsdf, wi: np.ndarray, black: bool = False):
    """sample_func, pdf_func for ``mi.chi2.ChiSquareTest`` at incidence wi (3,).

    wi reaches the kernel as an array (probe.interaction), not a literal: one kernel for all
    cells.  A sample counts when its weight is not 0 (Mitsuba marks a rejected sample so), or,
    with ``black``, when ``sample`` drew a direction (``bs.pdf > 0``) inside the support
    (``pdf(wo) > 0``; a rejected one keeps its bs.pdf): a black BSDF's weights are all 0, yet
    it draws its directions from its density.
    """
    delta = int(mi.BSDFFlags.Delta) | int(mi.BSDFFlags.Delta1D)

    def sample_func(sample):
        si = probe.interaction(wi[None], n=dr.width(sample))
        bs, weight = bsdf.sample(probe.context(), si, sample[0], mi.Point2f(sample[1], sample[2]))
        value = mi.unpolarized_spectrum(weight) if mi.is_polarized else weight
        if black:      # drawn, and inside the support (a rejected wo below the horizon is not)
            drawn = (bs.pdf > 0) & (bsdf.pdf(probe.context(), si, bs.wo) > 0)
        else:
            drawn = dr.any(value != 0)
        keep = drawn & ((mi.UInt32(bs.sampled_type) & delta) == 0)
        return bs.wo, dr.select(keep, mi.Float(1.0), mi.Float(0.0))

    def pdf_func(wo):
        return bsdf.pdf(probe.context(), probe.interaction(wi[None], n=dr.width(wo)), wo)

    return sample_func, pdf_func


def black_at(bsdf, wi: np.ndarray, opts) -> bool:
    """Whether ``eval`` is 0 at incidence wi for every direction sample() draws there and for
    random directions over the sphere (a black BSDF), from ``opts.n_finite`` lanes each."""
    r = lanes.rng(opts.seed, "chi2")
    n = opts.n_finite
    wis = np.repeat(np.asarray(wi, dtype=np.float64)[None], n, axis=0)
    s = probe.sample(bsdf, wis, r.random(n), r.random((n, 2)))
    d = lanes.sphere(r, n)
    ok = np.all(np.isfinite(s.wo), axis=1)
    return not (np.any(probe.eval(bsdf, wis[ok], s.wo[ok])) or np.any(probe.eval(bsdf, wis, d)))


def chi2_cell(bsdf, wi: np.ndarray, opts, level: float, seed: int) -> dict:
    """One χ² test at incidence wi; returns the cell's record (p-value, sums, verdict).

    A histogram of non-zero weights that is empty while ∫pdf > 0 is tested again on the
    drawn directions when the BSDF is black there (:func:`black_at`); else the cell fails.
    """
    wi = np.asarray(wi, dtype=np.float64)
    test, hist_sum, pdf_sum = _tabulate(bsdf, wi, opts, seed, black=False)
    black = hist_sum == 0 and pdf_sum >= 1e-6 and black_at(bsdf, wi, opts)
    if black:
        test, hist_sum, pdf_sum = _tabulate(bsdf, wi, opts, seed, black=True)
    if hist_sum == 0 and pdf_sum < 1e-6:
        return {"wi": wi.tolist(), "status": "empty", "hist_sum": 0.0, "pdf_sum": pdf_sum}
    ok = hist_sum > 0 and test.run(significance_level=level, test_count=1, quiet=True)
    p = float(test.p_value) if test.p_value is not None else 0.0
    cell = {"wi": wi.tolist(), "p_value": p if math.isfinite(p) else 0.0,
            "hist_sum": hist_sum / opts.chi2_samples, "pdf_sum": pdf_sum,
            "status": "pass" if ok else "fail", "messages": test.messages[-400:]}
    if black:
        cell["black"] = True
    if not ok:
        shape = (int(test.res.y), int(test.res.x))
        cell["histogram"] = np.array(test.histogram).reshape(shape).tolist()
        cell["expected"] = np.array(test.pdf).reshape(shape).tolist()
    return cell


def _tabulate(bsdf, wi: np.ndarray, opts, seed: int, black: bool):
    """The χ² test at wi with its histogram and pdf tabulated: (test, Σ histogram, Σ pdf)."""
    sample_func, pdf_func = _adapters(bsdf, wi, black)
    test = mi.chi2.ChiSquareTest(domain=mi.chi2.SphericalDomain(), sample_func=sample_func,
                                 pdf_func=pdf_func, sample_dim=3, sample_count=opts.chi2_samples,
                                 res=opts.chi2_res, ires=opts.chi2_ires, seed=seed)
    test.tabulate_histogram()
    test.tabulate_pdf()
    hist_sum = float(dr.sum(test.histogram)[0]) if dr.width(test.histogram) else 0.0
    return test, hist_sum, float(test.pdf_sum[0])


def chi2(bsdf, opts, m_tests: int) -> list[Row]:
    if lanes.delta_only(bsdf):
        return [delta_directions(bsdf, opts)]
    level = stats.sidak(stats.ALPHA, m_tests)
    cells = opts.cells(opts.chi2_cos, opts.chi2_phi)
    records = []
    for k, (theta, phi) in enumerate(cells):
        rec = chi2_cell(bsdf, probe.direction(theta, phi), opts, level, seed=opts.seed * 1000 + k)
        rec.update(theta_deg=math.degrees(theta), phi=phi)
        records.append(rec)
    tested = [r for r in records if r["status"] != "empty"]
    failed = [r for r in tested if r["status"] == "fail"]
    p_min = min((r["p_value"] for r in tested), default=1.0)
    where = ", ".join(f"θ_i={r['theta_deg']:.1f}° φ={r['phi']:.2f}" for r in failed)
    reason = (f"Pearson χ² of sample() vs pdf() (mi.chi2, {opts.chi2_samples} samples, "
              f"{opts.chi2_res}x{2 * opts.chi2_res} cells) at {len(tested)} incidence cells, "
              f"each at the Šidák level {level:.2e} of the BSDF's {m_tests} statistical tests; "
              f"delta samples excluded") + (f"; rejected at {where}" if failed else "")
    if not tested:
        return [Row("chi2", "sampling matches pdf", None, None, None, None, "skipped",
                    "the BSDF sampled nothing and has zero pdf at every tested incidence",
                    {"cells": records})]
    row = Row("chi2", "sampling matches pdf (min p-value)", p_min, level, None, level,
              "fail" if failed else "pass", reason, {"cells": records, "level": level})
    row.failing_lanes = {"cell": failed} if failed else None
    return [row]


def delta_directions(bsdf, opts) -> Row:
    """Delta-only BSDF: every sampled wo obeys reflection or Snell's law with bs.eta."""
    wi, _ = lanes.incident(opts.cells(), opts.n_identity)
    wi = wi[wi[:, 2] > 0]
    s = probe.sample_random(bsdf, wi, len(wi), seed=opts.seed + 1000 * lanes.SEED_OFFSETS["chi2"])
    live = np.any(s.weight != 0, axis=1) & np.all(np.isfinite(s.wo), axis=1)
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
