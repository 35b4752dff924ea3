r"""The topics read from the coefficients at the probe's points (:func:`.lanes.probe`):
``finite``, ``majorant``, ``albedo``, ``bounds`` and ``flags``.

What the integrators do with them (src/integrators/volpath.cpp at v3.9.1; volpathmis.cpp and
prbvolpath.py alike): ``sample_interaction`` draws a tentative collision at rate σ̄, the
majorant of the ray (medium.cpp:62-71); at it, a null collision is taken with probability
mean(σ_n/σ̄) (volpath.cpp:238) and weighted σ_n/P_null in the spectral path (244-246), a real
one weighted σ_s/mean(σ_t/σ̄) (262-264), or σ_s/σ_t in the grey path (265-266); ratio tracking
multiplies σ_n (514) or σ_n/σ̄ (516).  So:

``finite``.  σ_s, σ_n, σ_t and the majorant finite, σ_s, σ_t and σ̄ ≥ 0, at every point; the
bounds of ``intersect_aabb`` not NaN and mint ≤ maxt where it hits.  Tolerance 0 bad lanes.

``majorant``.  σ_t + σ_n = σ̄ (the two collision probabilities sum to 1 only then) to the
float32 identity tolerance ``roundoff.REL_TOL`` = 2⁻¹⁰ relative to max(σ_t + |σ_n|, σ̄);
σ_n ≥ −2⁻¹⁰ σ̄ (a negative σ_n is a negative probability: Mitsuba then takes every collision
as real, at rate σ̄ < σ_t).  At every in-bounds point of the probe, each with the majorant of
its ray as ``sample_interaction`` queries it (p = 0), and at every interaction
``sample_interaction`` itself returned (its ``combined_extinction``).

``albedo``.  σ_s/σ_t ≤ 1 + 2⁻¹⁰ where σ_t > 0 (a physical bound: judged inside the declared
domain by a sweep); σ_s ≥ 0 is ``finite``'s.

``bounds``.  σ_t = 0 at every probe point outside the interval ``intersect_aabb`` gives
(sample_interaction's rule, medium.cpp:53-60: no collision is ever sampled there, so a medium
that is not empty there is cut off), relative tolerance 2⁻²⁰ of the largest σ_t inside.  A
medium whose bounds are unbounded has no outside.

``flags``.  ``m_has_spectral_extinction`` false makes volpath take the grey path
(volpath.cpp:212-217, 265-266, 515-516): right only when σ_t and σ̄ are equal in every
channel (to 2⁻¹⁰ relative); ``m_is_homogeneous`` true makes volpath end the scene ray at the
sampled collision and never intersect again after a null collision (221, 480), and
prbvolpath's shadow rays use exp(−σ̄ t) as the transmittance (prbvolpath.py:404-406): right
only when σ_n = 0 and σ_t = σ̄ of the ray (to 2⁻¹⁰ of σ̄) at every point: one value along
each ray (a microflake medium's σ_t may still change with the direction).  A flag set where it
need not be (spectral extinction of a grey medium, a homogeneous medium not flagged) is
right and only slower: the row passes and says so.
"""

from __future__ import annotations

import mitsuba as mi
import numpy as np

from ..roundoff import REL_TOL
from . import lanes
from .topics import Row

#: σ_t outside the bounds, relative to the largest inside, that still counts as 0.
BOUNDS_TOL = 2.0 ** -20


def _worst(inputs: dict, k: int) -> dict:
    return {n: np.asarray(v)[k].tolist() for n, v in inputs.items()}


def _failing(row: Row, inputs: dict, bad: np.ndarray) -> Row:
    if row.status == "fail" and bad.any():
        row.failing_lanes = {n: np.asarray(v)[bad] for n, v in inputs.items()}
    return row


def _lanes(pts: dict) -> dict:
    return {"o": pts["o"], "d": pts["d"], "t": pts["t"]}


def _count_row(name, bad, total, what, inputs) -> Row:
    n_bad = int(np.sum(bad))
    details = {"lanes": int(total)}
    if n_bad:
        details["first_bad"] = _worst(inputs, int(np.flatnonzero(bad)[0]))
    row = Row("finite", name, float(n_bad), 0.0, None, 0.0, "pass" if n_bad == 0 else "fail",
              f"lanes where {what}, of {total}", details)
    return _failing(row, inputs, bad)


def finite(medium, opts) -> list[Row]:
    p = lanes.probe(medium, opts)
    pts = p.points()
    ss, sn, st, sm = pts["sigma_s"], pts["sigma_n"], pts["sigma_t"], pts["majorant"]
    bad_coef = (~np.all(np.isfinite(ss) & np.isfinite(sn) & np.isfinite(st), axis=1)
                | np.any(ss < 0, axis=1) | np.any(st < 0, axis=1))
    bad_maj = ~np.all(np.isfinite(sm), axis=1) | np.any(sm < 0, axis=1)
    hit = p.hit
    bad_aabb = np.isnan(p.mint) | np.isnan(p.maxt) | (hit & (p.mint > p.maxt))
    rays = {"o": p.o, "d": p.d}
    rows = [
        _count_row("get_scattering_coefficients: finite, σ_s ≥ 0, σ_t ≥ 0", bad_coef,
                   len(ss), "σ_s, σ_n or σ_t is NaN or infinite, or σ_s or σ_t < 0 (in-bounds "
                   "points uniform along the probe rays and those sample_interaction chose)",
                   _lanes(pts)),
        _count_row("get_majorant: finite, ≥ 0", bad_maj, len(sm),
                   "the majorant (queried as sample_interaction queries it) is NaN, infinite "
                   "or < 0", _lanes(pts)),
        _count_row("intersect_aabb: no NaN, mint ≤ maxt where it hits", bad_aabb, len(hit),
                   "a bound is NaN, or the mask is set with mint > maxt", rays),
    ]
    if len(p.coef_out[2]):
        out = p.coef_out[2]
        j = np.flatnonzero(p.outside)
        bad_out = ~np.all(np.isfinite(out), axis=1) | np.any(out < 0, axis=1)
        rows.append(_count_row("σ_t outside the bounds: finite, ≥ 0", bad_out, len(out),
                               "σ_t is NaN, infinite or < 0 at a point outside the bounds",
                               {"o": p.o[j], "d": p.d[j], "t": p.t_out[j]}))
    return rows


def _no_points(topic, name) -> Row:
    return Row(topic, name, None, None, None, None, "skipped",
               "no probe ray meets the medium's bounds inside the probe box (intersect_aabb "
               "misses every ray from [−box, box]³): nothing to judge", {})


def majorant(medium, opts) -> list[Row]:
    pts = lanes.probe(medium, opts).points()
    st, sn, sm = pts["sigma_t"], pts["sigma_n"], pts["majorant"]
    name_sum, name_neg = "σ_t + σ_n = majorant", "σ_n ≥ 0"
    if len(st) == 0:
        return [_no_points("majorant", name_sum), _no_points("majorant", name_neg)]
    ok = np.all(np.isfinite(st) & np.isfinite(sn) & np.isfinite(sm), axis=1)
    scale = np.maximum(np.maximum(st + np.abs(sn), np.abs(sm)), 1e-30)
    rel = np.where(ok[:, None], np.abs(st + sn - sm) / scale, 0.0).max(axis=1)
    excess = rel / REL_TOL
    inputs = {**_lanes(pts), "sigma_t": st, "sigma_n": sn, "majorant": sm}
    k = int(np.argmax(excess))
    n_sampled = int(np.sum(pts["source"] == "sampled"))
    where = (f"{len(st)} in-bounds points ({len(st) - n_sampled} uniform along the probe rays, "
             f"{n_sampled} chosen by sample_interaction), each with its ray's majorant as "
             f"sample_interaction queries it")
    row1 = Row("majorant", name_sum, float(excess[k]), 0.0, None, 1.0,
               "pass" if excess[k] <= 1.0 else "fail",
               f"measured = max |σ_t + σ_n − majorant| / max(σ_t + |σ_n|, majorant) / 2^-10 "
               f"over {where}; must be ≤ 1 (the null and real collision probabilities of the "
               f"integrators sum to 1 only then); {int((~ok).sum())} non-finite lanes left out "
               f"(the finite topic's)",
               {"lanes": len(st), "worst": _worst(inputs, k), "relation": "<="})
    _failing(row1, inputs, excess > 1.0)
    neg = np.where(ok[:, None], sn / np.maximum(np.abs(sm), 1e-30), 0.0).min(axis=1)
    j = int(np.argmin(neg))
    row2 = Row("majorant", name_neg, float(neg[j]), 0.0, None, REL_TOL,
               "pass" if neg[j] >= -REL_TOL else "fail",
               f"measured = min σ_n / majorant over {where}; must be ≥ −2^-10 (a negative σ_n "
               f"is a negative null-collision probability: the integrators then take every "
               f"collision as real, at the majorant's rate instead of σ_t's)",
               {"lanes": len(st), "worst": _worst(inputs, j), "relation": ">="})
    return [row1, _failing(row2, inputs, neg < -REL_TOL)]


def albedo(medium, opts) -> list[Row]:
    pts = lanes.probe(medium, opts).points()
    ss, st = pts["sigma_s"], pts["sigma_t"]
    name = "σ_s / σ_t ≤ 1"
    if len(st) == 0:
        return [_no_points("albedo", name)]
    live = np.isfinite(ss) & np.isfinite(st) & (st > 0)
    a = np.where(live, ss / np.where(live, st, 1.0), 0.0)
    worst = a.max(axis=1)
    k = int(np.argmax(worst))
    inputs = {**_lanes(pts), "sigma_s": ss, "sigma_t": st}
    ok = worst[k] <= 1.0 + REL_TOL
    row = Row("albedo", name, float(worst[k]), 1.0, None, REL_TOL, "pass" if ok else "fail",
              f"measured = max σ_s/σ_t over the channels with σ_t > 0 at {len(st)} in-bounds "
              f"points (the single-scattering albedo: above 1 a real collision adds energy, "
              f"σ_s/σ_t being the integrators' weight); tolerance 2^-10",
              {"lanes": len(st), "channels_with_sigma_t_0": int((~live).sum()),
               "min_albedo": float(np.min(np.where(live, a, np.inf))) if live.any() else None,
               "worst": _worst(inputs, k), "relation": "<="})
    return [_failing(row, inputs, worst > 1.0 + REL_TOL)]


def bounds(medium, opts) -> list[Row]:
    p = lanes.probe(medium, opts)
    name = "σ_t = 0 outside intersect_aabb's bounds"
    j = np.flatnonzero(p.outside)
    if not len(j):
        return [Row("bounds", name, 0.0, 0.0, None, 0.0, "pass",
                    f"intersect_aabb bounds every one of {len(p.o)} probe rays by the probe box "
                    f"[−{opts.box:g}, {opts.box:g}]³ or more (an unbounded medium): there is no "
                    f"outside to check", {"rays": len(p.o)})]
    st_out = p.coef_out[2]
    st_in = p.points()["sigma_t"]
    ref = float(np.nanmax(st_in)) if len(st_in) and np.isfinite(st_in).any() else 0.0
    ref = ref if ref > 0 else float(np.nanmax(st_out)) if np.isfinite(st_out).any() else 1.0
    ref = ref if ref > 0 else 1.0
    rel = np.nan_to_num(st_out, nan=0.0, posinf=np.inf).max(axis=1) / ref
    k = int(np.argmax(rel))
    inputs = {"o": p.o[j], "d": p.d[j], "t": p.t_out[j], "sigma_t": st_out}
    inside = int(p.inside.sum())
    ok = rel[k] <= BOUNDS_TOL
    pos = p.o[j] + p.t_out[j][:, None] * p.d[j]
    row = Row("bounds", name, float(rel[k]), 0.0, None, BOUNDS_TOL, "pass" if ok else "fail",
              f"measured = max σ_t / (the largest σ_t inside the bounds, {ref:.4g}) at {len(j)} "
              f"points of the probe rays outside the interval intersect_aabb returns (and "
              f"inside the box [−{opts.box:g}, {opts.box:g}]³); sample_interaction never "
              f"samples a collision there, so the medium is cut off where σ_t > 0; "
              f"{inside} of {len(p.o)} rays meet the bounds",
              {"points": len(j), "sigma_t_inside_max": ref,
               "positive_outside": int((rel > BOUNDS_TOL).sum()),
               "worst": {**_worst(inputs, k), "p": pos[k].tolist()}, "relation": "<="})
    if not ok:
        bad = rel > BOUNDS_TOL
        row.failing_lanes = {"p": pos[bad], "sigma_t": st_out[bad]}
    return [row]


def _spread(x: np.ndarray) -> np.ndarray:
    """Per lane: (max − min)/max over the channels (0 where all are 0)."""
    hi = np.max(np.abs(x), axis=1)
    return np.where(hi > 0, (x.max(axis=1) - x.min(axis=1)) / np.where(hi > 0, hi, 1.0), 0.0)


def flags(medium, opts) -> list[Row]:
    f = lanes.flags(medium)
    pts = lanes.probe(medium, opts).points()
    st, sn, sm = pts["sigma_t"], pts["sigma_n"], pts["majorant"]
    rows = []
    n = len(st)
    c = lanes.channels()
    name_s = "has_spectral_extinction where σ_t's channels differ"
    if n == 0:
        return [_no_points("flags", name_s), _no_points("flags", "is_homogeneous only where "
                                                         "σ_n = 0 and σ_t = majorant")]
    ok = np.all(np.isfinite(st) & np.isfinite(sm), axis=1)
    spread = np.where(ok, np.maximum(_spread(st), _spread(sm)), 0.0)
    k = int(np.argmax(spread))
    inputs = {**_lanes(pts), "sigma_t": st, "majorant": sm}
    grey = spread[k] <= REL_TOL
    if c == 1:
        rows.append(Row("flags", name_s, 0.0, 0.0, None, REL_TOL, "pass",
                        f"one channel in {mi.variant()}: the flag changes "
                        f"nothing", {"has_spectral_extinction": f["has_spectral_extinction"]}))
    elif f["has_spectral_extinction"]:
        rows.append(Row("flags", name_s, float(spread[k]), None, None, None, "pass",
                        "m_has_spectral_extinction is set: the integrators take the spectral "
                        "path, right whatever the channels" + (
                            "; σ_t and the majorant are equal in every channel at all "
                            f"{n} points, so the grey path (flag unset) would be right and "
                            "faster" if grey else
                            f"; σ_t or the majorant differ between channels by up to "
                            f"{spread[k]:.3g} (relative), which needs it"),
                        {"has_spectral_extinction": True, "lanes": n}))
    else:
        row = Row("flags", name_s, float(spread[k]), 0.0, None, REL_TOL,
                  "pass" if grey else "fail",
                  f"m_has_spectral_extinction is unset: volpath takes the grey path (a real "
                  f"collision weighted σ_s/σ_t, a null one σ_n/σ̄ per channel, distances "
                  f"drawn with one channel's majorant), right only where σ_t and the majorant "
                  f"are equal in every channel; measured = max (max − min)/max over the "
                  f"channels of σ_t and of the majorant at {n} in-bounds points, must be ≤ "
                  f"2^-10",
                  {"has_spectral_extinction": False, "lanes": n, "worst": _worst(inputs, k),
                   "relation": "<="})
        rows.append(_failing(row, inputs, spread > REL_TOL))
    name_h = "is_homogeneous only where σ_n = 0 and σ_t = majorant"
    okh = np.all(np.isfinite(st) & np.isfinite(sn) & np.isfinite(sm), axis=1)
    scale = np.maximum(np.max(np.abs(sm), axis=1), 1e-30)
    null = np.where(okh, np.max(np.abs(sn), axis=1) / scale, 0.0)
    vary = np.where(okh, np.max(np.abs(st - sm), axis=1) / scale, 0.0)
    var = np.maximum(null, vary)
    k = int(np.argmax(var))
    constant = var[k] <= REL_TOL
    inputs = {**_lanes(pts), "sigma_t": st, "sigma_n": sn, "majorant": sm}
    if f["is_homogeneous"]:
        row = Row("flags", name_h, float(var[k]), 0.0, None, REL_TOL,
                  "pass" if constant else "fail",
                  f"m_is_homogeneous is set: volpath ends the scene ray at the sampled "
                  f"collision and does not intersect again after a null collision, prbvolpath "
                  f"takes exp(−majorant·t) as a shadow ray's transmittance: right only where "
                  f"σ_n = 0 and σ_t is the majorant of the ray (one value along it); measured "
                  f"= max over {n} in-bounds points of |σ_n| and |σ_t − majorant|, relative to "
                  f"the majorant, must be ≤ 2^-10",
                  {"is_homogeneous": True, "lanes": n, "worst": _worst(inputs, k),
                   "max_sigma_n_over_majorant": float(null.max()),
                   "max_sigma_t_off_majorant": float(vary.max()), "relation": "<="})
        rows.append(_failing(row, inputs, var > REL_TOL))
    else:
        rows.append(Row("flags", name_h, float(var[k]), None, None, None, "pass",
                        "m_is_homogeneous is unset: the integrators track collisions, right "
                        "whatever the medium" + (
                            f"; σ_n = 0 and σ_t = majorant at all {n} points, so the flag "
                            "would be right and faster" if constant else ""),
                        {"is_homogeneous": False, "lanes": n}))
    return rows
