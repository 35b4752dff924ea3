r"""The identity topics of an emitter: ``finite``, ``weight`` and ``pdf``.

Mitsuba's conventions (3.9.1, commit 478e193a), which every emitter must keep:

* ``sample_direction(it, u)`` returns (ds, weight) with ds.pdf the density of ds.d in solid
  angle at it.p and weight = radiance / ds.pdf: for an area light
  L_e(ds.p, −ds.d) / ds.pdf with ds.pdf = p_A(ds.p) · dist² / |cos θ'| (src/emitters/area.cpp,
  ``sample_direction``: ``m_radiance->eval(si) / ds.pdf``, the shape's pdf already converted,
  e.g. src/shapes/sphere.cpp ``sample_direction``: uniform cone pdf outside, m_inv_surface_area ·
  dist²/|cos| inside); for an environment L(ds.d) / ds.pdf (constant.cpp: uniform sphere pdf
  1/4π); for a delta light ds.pdf = 1 and ds.delta set, the weight being the whole
  contribution: I / r² for a point (point.cpp: ``m_intensity->eval(si) * sqr(inv_dist)``),
  I · falloff / r² for a spot (spot.cpp), the irradiance E for a directional light;
* ``pdf_direction(it, ds)`` is the same solid-angle density (area.cpp ``pdf_direction``:
  ``m_shape->pdf_direction``; 0 on the back side, dot(ds.d, ds.n) ≥ 0);
* ``eval_direction(it, ds)`` is the radiance (intensity / r², irradiance for delta lights)
  that arrives at it.p from ds; ``eval(si)`` is the radiance leaving the surface point si
  towards si.wi (area.cpp: 0 unless cos θ(si.wi) > 0).

Rows.  ``finite``: every output of sample_direction, pdf_direction, eval, sample_ray and
sample_position is finite and ≥ 0 over all reference points and sample values (edges
included); ``measured`` is the number of bad lanes, tolerance 0.  ``weight``: weight · ds.pdf
equals eval_direction(ds) (float32 round-off, ``roundoff.REL_TOL`` = 2⁻¹⁰ relative, with
``rel_diff``'s floor), and for non-delta emitters it equals the radiance ``eval`` returns at
the point a ray from it.p along ds.d hits (traced in a scene holding the shape alone; an
environment's at si.wi = −ds.d), to REL_TOL plus the lane's sensitivity to an 8u move of the
ray (``roundoff.sensitivity``; a textured radiance changes along the surface).  ``pdf``:
ds.pdf = pdf_direction(ds) on every lane with a non-zero weight, to REL_TOL plus, on a lane
that exceeds it, pdf_direction's sensitivity to an 8u move of ds.d (the reference point held
exact: an environment map's pdf near a pole, where θ = acos(d.y) is ill-conditioned); for delta
emitters, ds.delta is set and ds.pdf = 1.  No sensitivity allowance covers a lane on the rim
of a sunsky's sun cone (:func:`sun_rim`): there sample_direction and pdf_direction/eval disagree
on whether the very same ds.d is a sun direction (sunsky.h:430 against 946), which findings
sunsky-sun-rim-pdf and -weight explain.  The identity topics drop non-finite lanes (the
``finite`` topic's) and count them.
"""

from __future__ import annotations

import numpy as np

from ... import probe
from ..roundoff import REL_TOL, invalid, rel_diff, sensitivity
from . import lanes as lanes_
from .config import rng
from .setup import Setup, float_, point2, sphere_dirs, sun_rim_ulps
from .signatures import on_rim
from .topics import Row

ROUND_OFF = "float32 round-off tolerance 2^-10 relative (roundoff.REL_TOL)"


def bounded(topic, name, values, tol, reason, details, inputs=None) -> Row:
    """A row passing when the largest finite lane value is ≤ tol; it carries the inputs of
    its failing lanes (``failing_lanes``) for documented causes' signatures."""
    values = np.asarray(values, np.float64)
    finite = values[np.isfinite(values)]
    measured = float(finite.max()) if finite.size else 0.0
    ok = measured <= tol
    if values.size and not ok:
        k = int(np.nanargmax(np.where(np.isfinite(values), values, -1.0)))
        details = {**details, "worst_lane": {n: np.asarray(v)[k].tolist()
                                             for n, v in (inputs or {}).items()}}
    row = Row(topic, name, measured, 0.0, None, tol, "pass" if ok else "fail", reason, details)
    if not ok and inputs is not None:
        bad = np.isfinite(values) & (values > tol)
        row.failing_lanes = {n: np.asarray(v)[bad] for n, v in inputs.items()}
    return row


def lane_inputs(setup: Setup, s, mask) -> dict:
    """The per-lane inputs a failing row records: reference point, sample value, group, for a
    sphere |p − c|/r − 1 (where the reference point lies relative to its surface), and for
    Mitsuba's sunsky how far ds.d lies inside its sun's cone by sunsky.h's own float32 test
    (``sun_rim_ulps``, :func:`.setup.sun_rim_ulps`: negative outside)."""
    out = {"ref": s.p[mask], "u": s.u[mask], "group": s.group[mask]}
    sph = setup.sphere
    if sph is not None:
        c, r = sph
        out["rel_radius"] = np.linalg.norm(s.p[mask] - c, axis=1) / r - 1.0
    if setup.sun is not None:
        out["sun_rim_ulps"] = sun_rim_ulps(setup.sun, s.d[mask])
    return out


def sun_rim(setup: Setup, s) -> np.ndarray:
    """Lanes whose ds.d lies within a few float32 steps of the rim of the sun's cone by
    sunsky.h's own test, where sample_direction decides sun or sky by another test than
    pdf_direction and eval (sunsky.h:430 against 946): the signature of findings
    sunsky-sun-rim-pdf and -weight (:class:`.signatures.SunConeRim`).  A Mitsuba
    inconsistency, not rounding of the check: the sensitivity allowance of the pdf and
    traced-point rows never covers them (one explanation per phenomenon)."""
    if setup.sun is None:
        return np.zeros(s.n, bool)
    return on_rim(sun_rim_ulps(setup.sun, s.d))


def _count_row(name, bad, total, what, details=None, values=()) -> Row:
    """``values``: the arrays checked; a failing row records, per failing lane, whether its
    values were all finite and only negative (``failing_lanes["negative_only"]``)."""
    n_bad = int(np.sum(bad))
    row = Row("finite", name, float(n_bad), 0.0, None, 0.0, "pass" if n_bad == 0 else "fail",
              f"lanes where {what} is NaN, infinite or negative, of {total} (reference "
              f"points x sample values, edges 0 and 1-eps included)", details or {})
    if n_bad and values:
        row.failing_lanes = {"negative_only": (~_nonfinite(*values) & invalid(*values))[bad]}
    return row


def _nonfinite(*arrays) -> np.ndarray:
    out = None
    for a in arrays:
        b = ~np.isfinite(np.asarray(a, np.float64))
        b = b.any(axis=1) if b.ndim > 1 else b
        out = b if out is None else out | b
    return out


def finite(setup: Setup, opts) -> list[Row]:
    s = lanes_.sample(setup, opts, "finite")
    e, n = setup.calls, s.n
    rows = []
    marked = (s.pdf == 0) & np.all(s.weight == 0, axis=1)     # an invalid sample, so marked
    bad = invalid(s.pdf, s.weight) | (~np.all(np.isfinite(s.d), axis=1) & ~marked)
    rows.append(_count_row("sample_direction: ds.pdf, ds.d, weight", bad, n,
                           "ds.pdf or the weight (or ds.d non-finite in a sample not marked "
                           "invalid by pdf = weight = 0)", _firstinvalid(s, bad),
                           (s.pdf, s.weight, np.where(marked[:, None], 0.0, s.d))))
    pdf = probe.to_numpy(e.pdf_direction(s.it, s.ds), n)
    rows.append(_count_row("pdf_direction at the sampled ds", invalid(pdf), n, "pdf_direction",
                           _firstinvalid(s, invalid(pdf))))
    ev = probe.to_numpy(e.eval_direction(s.it, s.ds), n)
    row = _count_row("eval_direction at the sampled ds", invalid(ev), n, "eval_direction",
                     _firstinvalid(s, invalid(ev)), (ev,))
    if row.status == "fail":           # for documented causes' signatures (the sample's pdf)
        row.failing_lanes.update(pdf=s.pdf[invalid(ev)], ref=s.p[invalid(ev)])
    rows.append(row)
    if not setup.delta:
        d = s.d if setup.kind == "infinite" else sphere_dirs(rng(opts.seed, "finite"), n)
        value, _ = lanes_.traced_radiance(setup, s.p, d)
        rows.append(_count_row("eval along rays from the reference points", invalid(value), n,
                               "eval (radiance seen along a ray)", values=(value,)))
    r = rng(opts.seed, "finite")
    u = lanes_.with_edges(r.random((n, 5)), n)
    ray, w = e.sample_ray(float_(np.zeros(n)), float_(u[:, 4]), point2(u[:, :2]),
                          point2(u[:, 2:4]))
    wr = probe.to_numpy(w, n)
    bad = invalid(wr) | ~np.all(np.isfinite(probe.to_numpy(ray.d, n)), axis=1) | \
        ~np.all(np.isfinite(probe.to_numpy(ray.o, n)), axis=1)
    rows.append(_count_row("sample_ray: weight, ray", bad, n, "the sample_ray weight (or the "
                           "ray non-finite)", values=(wr, probe.to_numpy(ray.d, n),
                                                      probe.to_numpy(ray.o, n))))
    if setup.kind in ("surface", "position"):
        ps, pw = e.sample_position(float_(np.zeros(n)), point2(u[:, :2]))
        bad = invalid(probe.to_numpy(ps.pdf, n), probe.to_numpy(pw, n))
        rows.append(_count_row("sample_position: ps.pdf, weight", bad, n,
                               "ps.pdf or the position weight"))
    return rows


def _firstinvalid(s, bad) -> dict:
    if not np.any(bad):
        return {}
    k = int(np.flatnonzero(bad)[0])
    return {"first_bad": {"ref": s.p[k].tolist(), "u": s.u[k].tolist(),
                          "group": s.groups[s.group[k]].label}}


def weight(setup: Setup, opts) -> list[Row]:
    s = lanes_.sample(setup, opts, "weight")
    live = s.live
    lhs = s.weight * s.pdf[:, None]
    ev = probe.to_numpy(setup.calls.eval_direction(s.it, s.ds), s.n)
    rel = np.where(live, np.max(np.nan_to_num(rel_diff(lhs, ev), nan=np.inf), axis=1), 0.0)
    inputs = lane_inputs(setup, s, np.ones(s.n, bool))
    if setup.delta:
        return [bounded("weight", "weight x ds.pdf = eval_direction(ds)", rel, REL_TOL,
                        f"max over {int(live.sum())} sampled lanes of rel_diff(weight·ds.pdf, "
                        f"eval_direction(ds)); {ROUND_OFF}", {"lanes": int(live.sum())}, inputs)]
    # both sides at the same ds: no rounding lies between them, so round-off alone (the
    # sun-rim lanes of sunsky.h:430, where they differ by the sun's whole radiance, are
    # finding sunsky-sun-rim-weight, not conditioning of this check)
    rows = [bounded("weight", "weight x ds.pdf = eval_direction(ds)", rel, REL_TOL,
                    f"max over {int(live.sum())} sampled lanes of rel_diff(weight·ds.pdf, "
                    f"eval_direction(ds)), both at the same ds; {ROUND_OFF}",
                    {"lanes": int(live.sum())}, inputs)]
    value, t = lanes_.traced_radiance(setup, s.p, s.d)
    same = np.isinf(t) if setup.kind == "infinite" else \
        np.abs(t - s.dist) <= 1e-3 * np.maximum(s.dist, 1e-3)
    keep = live & same

    def traced(p, d):
        # not renormalized: that would undo the move of a component near ±1, the one whose
        # rounding acos(d.y) (an environment's θ near a pole) amplifies (roundoff.perturb)
        return lanes_.traced_radiance(setup, p, d)[0]

    sens = np.zeros(s.n)
    if keep.any():
        sens[keep] = sensitivity(traced, s.p[keep], s.d[keep], rng(opts.seed, "weight"),
                                 value=value[keep])
    sens[sun_rim(setup, s)] = 0.0
    rel = np.max(np.nan_to_num(rel_diff(lhs, value), nan=np.inf), axis=1)
    excess = np.where(keep, rel / (REL_TOL + sens), 0.0)
    rows.append(bounded(
        "weight", "weight x ds.pdf = eval at the traced point", excess, 1.0,
        f"measured = max over {int(keep.sum())} lanes of rel_diff(weight·ds.pdf, eval at the "
        f"point a ray from the reference point along ds.d hits) / (2^-10 + the radiance's "
        f"sensitivity to an 8u move of the ray), must be ≤ 1; {int((live & ~same).sum())} "
        f"sampled lanes whose ray hits the shape elsewhere (|t − ds.dist| > 1e-3 dist) left out",
        {"lanes": int(keep.sum()), "ray_elsewhere": int((live & ~same).sum())}, inputs))
    return rows


def pdf(setup: Setup, opts) -> list[Row]:
    s = lanes_.sample(setup, opts, "pdf")
    inputs = lane_inputs(setup, s, np.ones(s.n, bool))
    live = s.live
    if setup.delta:
        bad = live & ~(s.delta & (s.pdf == 1.0))
        return [bounded("pdf", "delta: ds.delta set and ds.pdf = 1", bad.astype(float), 0.0,
                        f"lanes (of {int(live.sum())} sampled) where ds.delta is not set or "
                        f"ds.pdf ≠ 1 (Mitsuba's convention for a delta light: the weight is "
                        f"the whole contribution)", {"lanes": int(live.sum())}, inputs)]
    pd = probe.to_numpy(setup.calls.pdf_direction(s.it, s.ds), s.n)
    rel = np.where(live, np.nan_to_num(rel_diff(s.pdf, pd), nan=np.inf), 0.0)
    sens = np.zeros(s.n)
    check = np.flatnonzero(rel > REL_TOL)
    if check.size:
        def towards(index, d):      # the reference point stays exact: only ds.d is rounded
            lane = check[np.rint(index[:, 0]).astype(int) % len(check)]
            return lanes_.pdf_towards(setup, s.p[lane], d)    # not renormalized, as above
        index = np.repeat(np.arange(len(check), dtype=np.float64)[:, None], 3, axis=1)
        sens[check] = sensitivity(towards, index, s.d[check], rng(opts.seed, "pdf"))
    sens[sun_rim(setup, s)] = 0.0
    excess = rel / (REL_TOL + sens)
    worst = int(np.argmax(excess)) if excess.size else 0
    return [bounded("pdf", "ds.pdf = pdf_direction(ds)", excess, 1.0,
                    f"measured = max over {int(live.sum())} sampled lanes of rel_diff(ds.pdf, "
                    f"pdf_direction(ds)), both in solid angle at the reference point, / (2^-10 + "
                    f"pdf_direction's sensitivity to an 8u move of ds.d, the reference point "
                    f"held exact), must be ≤ 1", {"lanes": int(live.sum()),
                                     "worst_ds_pdf": float(s.pdf[worst]),
                                     "worst_pdf_direction": float(pd[worst]),
                                     "worst_group": s.groups[s.group[worst]].label}, inputs)]

