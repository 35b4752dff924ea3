r"""The identity topics of a phase function: ``finite``, ``weight``, ``pdf``, ``reciprocity``.

Mitsuba's interface (3.9.1, include/mitsuba/render/phase.h): ``sample(ctx, mi, u1, u2)``
returns (wo, weight, pdf) with pdf the density of wo in solid angle and weight =
value(wo)/pdf (1 for a phase function sampled exactly, hg.cpp line 89); ``eval_pdf(ctx, mi,
wo)`` returns (value, pdf).  The direction convention is :mod:`.lanes`'.

Rows.  ``finite``: every output of sample (wo, weight, pdf) and of eval_pdf, at uniform
(wi, wo) over the whole sphere and at the sampled wo, is finite and ≥ 0, over (wi, u) lanes
with the six axis directions and the sample-value corners {0, 1 − 2⁻²⁴}³ first; an invalid
sample marked by pdf = weight = 0 may have any wo; tolerance 0 bad lanes.  ``weight``: the
sample weight equals value/pdf of eval_pdf at the sampled wo, to ``roundoff.REL_TOL`` =
2⁻¹⁰ relative (``rel_diff`` with its floor) plus, on a lane that exceeds it, the ratio's
sensitivity to an 8u move of (wi, wo) (``roundoff.sensitivity``) and, where that is not
enough, to every wo within ±8 ulps per component (``roundoff.refine``, the BSDF topic's).  ``pdf``: the pdf sample
reports equals eval_pdf's pdf at the sampled wo, to the same tolerance (a g = 0.99 lobe moves
by 0.3 % per 1e-7 of cos θ: the sensitivity term, never a wider constant).  ``reciprocity``:
σ(wi) f(wi, wo) = σ(wo) f(wo, wi), f the value of eval_pdf, σ ``projected_area`` (1 for a
phase function that is not a microflake model; the microflake form is Jakob et al. 2010's
σ(ω) f(ω → ω') reciprocal), at uniform pairs and at pairs within 0.05 of forward and backward
scattering, to the same tolerance.  The identity rows leave out lanes with a non-finite
input (the ``finite`` topic's) and count them.
"""

from __future__ import annotations

import numpy as np

from ..roundoff import REL_TOL, invalid, refine, rel_diff, sensitivity
from . import lanes
from .config import rng
from .topics import Row

ROUND_OFF = ("float32 round-off tolerance 2^-10 relative (roundoff.REL_TOL) plus the "
             "lane's sensitivity to an 8u move of (wi, wo), or to wo's ±8-ulp box, where it "
             "exceeds that")


def bounded(topic, name, values, tol, reason, details, inputs=None) -> Row:
    """A row passing when the largest finite lane value is ≤ tol; a failing row records the
    worst lane and the inputs of its failing lanes (``failing_lanes``)."""
    values = np.asarray(values, np.float64)
    if values.size == 0:
        return Row(topic, name, None, None, None, tol, "skipped", "no lane to check: every "
                   "sample is non-finite or has pdf 0 (the finite topic's)", details)
    finite = values[np.isfinite(values)]
    measured = float(finite.max()) if finite.size else 0.0
    ok = measured <= tol
    row = Row(topic, name, measured, 0.0, None, tol, "pass" if ok else "fail", reason, details)
    if not ok and inputs is not None:
        k = int(np.nanargmax(np.where(np.isfinite(values), values, -1.0)))
        row.details["worst_lane"] = {n: np.asarray(v)[k].tolist() for n, v in inputs.items()}
        bad = np.isfinite(values) & (values > tol)
        row.failing_lanes = {n: np.asarray(v)[bad] for n, v in inputs.items()}
    return row


def _count(name, bad, total, what, wi, other, label) -> Row:
    n_bad = int(np.sum(bad))
    details = {}
    if n_bad:
        k = int(np.flatnonzero(bad)[0])
        details["first_bad"] = {"wi": wi[k].tolist(), label: other[k].tolist()}
    row = Row("finite", name, float(n_bad), 0.0, None, 0.0, "pass" if n_bad == 0 else "fail",
              f"lanes where {what} is NaN, infinite or negative, of {total} (wi over the "
              f"sphere, axes and sample-value corners included)", details)
    if n_bad:
        row.failing_lanes = {"wi": wi[bad], label: other[bad]}
    return row


def draws(phase, opts, topic):
    """(wi, u, wo, weight, pdf) of sample() at the topic's seeded lanes."""
    r = rng(opts.seed, topic)
    n = opts.n_lanes
    wi = lanes.sphere(r, n)
    u = lanes.with_edges(r.random((n, 3)))
    wo, w, p = lanes.sample(phase, wi, u[:, 0], u[:, 1:])
    return wi, u, wo, w, p


def finite(phase, opts) -> list[Row]:
    wi, u, wo, w, p = draws(phase, opts, "finite")
    n = len(wi)
    marked = (p == 0) & np.all(w == 0, axis=1)
    bad = invalid(p, w) | (~np.all(np.isfinite(wo), axis=1) & ~marked)
    rows = [_count("sample: wo, weight, pdf", bad, n, "the pdf or the weight (or wo, in a sample "
                   "not marked invalid by pdf = weight = 0)", wi, u, "u")]
    r = rng(opts.seed, "finite")
    wi2, wo2 = lanes.sphere(r, n), lanes.sphere(r, n)[::-1]
    v, q = lanes.eval_pdf(phase, wi2, wo2)
    rows.append(_count("eval_pdf at uniform (wi, wo): value, pdf", invalid(v, q), n,
                       "eval_pdf's value or pdf", wi2, wo2, "wo"))
    ok = np.all(np.isfinite(wo), axis=1)
    v, q = lanes.eval_pdf(phase, wi[ok], wo[ok])
    rows.append(_count("eval_pdf at the sampled wo: value, pdf", invalid(v, q), int(ok.sum()),
                       "eval_pdf's value or pdf", wi[ok], wo[ok], "wo"))
    return rows


def _live(wo, w, p):
    return (np.all(np.isfinite(wo), axis=1) & np.all(np.isfinite(w), axis=1)
            & np.isfinite(p) & (p > 0))


def _ratio(phase):
    def fn(wi, wo):
        v, q = lanes.eval_pdf(phase, wi, wo)
        return np.where(q[:, None] > 0, v / np.where(q > 0, q, 1.0)[:, None], 0.0)
    return fn


def _checked(rel, fn, wi, wo, r, value=None):
    """rel / (REL_TOL + sensitivity) per lane: the random 8u estimate where rel > REL_TOL, then
    for lanes still failing the ±8-ulp box of wo (``roundoff.refine``, worst first)."""
    sens = np.zeros(len(rel))
    check = np.flatnonzero(rel > REL_TOL)
    if check.size:
        value = fn(wi, wo) if value is None else value
        sens[check] = sensitivity(fn, wi[check], wo[check], r, value=value[check])
        return refine(rel, sens, np.zeros(len(rel)), fn, wi, wo, value)[0]
    return rel / REL_TOL


def weight(phase, opts) -> list[Row]:
    wi, u, wo, w, p = draws(phase, opts, "weight")
    live = _live(wo, w, p)
    wi, u, wo, w = wi[live], u[live], wo[live], w[live]
    v, q = lanes.eval_pdf(phase, wi, wo)
    keep = np.isfinite(q) & (q > 0) & np.all(np.isfinite(v), axis=1)
    ratio = np.where(keep[:, None], v / np.where(keep, q, 1.0)[:, None], 0.0)
    rel = np.where(keep, np.max(np.nan_to_num(rel_diff(w, ratio), nan=np.inf), axis=1), 0.0)
    excess = _checked(rel, _ratio(phase), wi, wo, rng(opts.seed, "weight"), ratio)
    return [bounded("weight", "weight = value/pdf of eval_pdf at the sampled wo", excess, 1.0,
                    f"measured = max over {int(keep.sum())} sampled lanes of rel_diff(weight, "
                    f"value/pdf) / (2^-10 + its sensitivity), must be ≤ 1; {ROUND_OFF}; "
                    f"{int((~live).sum())} lanes with pdf 0 or non-finite outputs and "
                    f"{int((~keep).sum())} where eval_pdf's pdf is 0 left out",
                    {"lanes": int(keep.sum()), "dropped": int((~live).sum())},
                    {"wi": wi, "u": u, "wo": wo})]


def pdf(phase, opts) -> list[Row]:
    wi, u, wo, w, p = draws(phase, opts, "pdf")
    live = _live(wo, w, p)
    wi, u, wo, p = wi[live], u[live], wo[live], p[live]
    q = lanes.pdf(phase, wi, wo)
    rel = np.nan_to_num(rel_diff(p, q), nan=np.inf)
    excess = _checked(rel, lambda a, b: lanes.pdf(phase, a, b), wi, wo,
                      rng(opts.seed, "pdf"), q)
    worst = int(np.argmax(excess)) if excess.size else 0
    return [bounded("pdf", "sample's pdf = eval_pdf's pdf at wo", excess, 1.0,
                    f"measured = max over {int(live.sum())} sampled lanes of rel_diff(pdf of "
                    f"sample, pdf of eval_pdf(wo)) / (2^-10 + its sensitivity), must be ≤ 1; "
                    f"{ROUND_OFF}", {"lanes": int(live.sum()),
                                     "worst_sample_pdf": float(p[worst]) if p.size else None,
                                     "worst_eval_pdf": float(q[worst]) if q.size else None},
                    {"wi": wi, "u": u, "wo": wo})]


def reciprocity(phase, opts) -> list[Row]:
    r = rng(opts.seed, "reciprocity")
    n = opts.n_lanes
    wi = lanes.sphere(r, n)
    wo = lanes.sphere(r, n)[::-1].copy()
    k = n // 4                       # a quarter near forward and a quarter near backward
    for sign, part in ((-1.0, slice(0, k)), (1.0, slice(k, 2 * k))):
        d = sign * wi[part] + 0.05 * lanes.sphere(r, k)
        wo[part] = d / np.linalg.norm(d, axis=1)[:, None]

    def sym(a, b):
        return lanes.projected_area(phase, a)[:, None] * lanes.value(phase, a, b)

    f1, f2 = sym(wi, wo), sym(wo, wi)
    ok = np.all(np.isfinite(f1), axis=1) & np.all(np.isfinite(f2), axis=1)
    rel = np.where(ok, np.max(np.nan_to_num(rel_diff(f1, f2), nan=0.0), axis=1), 0.0)
    excess = _checked(rel, sym, wi, wo,
                      rng(opts.seed, "reciprocity"), f1)
    return [bounded("reciprocity", "σ(wi) f(wi, wo) = σ(wo) f(wo, wi)", excess, 1.0,
                    f"measured = max over {int(ok.sum())} (wi, wo) pairs (uniform, and within "
                    f"0.05 of forward and backward scattering) of rel_diff / (2^-10 + its "
                    f"sensitivity), must be ≤ 1; f = eval_pdf's value, σ = projected_area; "
                    f"{int((~ok).sum())} pairs with a non-finite value left out",
                    {"lanes": int(ok.sum()), "nonfinite": int((~ok).sum())},
                    {"wi": wi, "wo": wo})]
