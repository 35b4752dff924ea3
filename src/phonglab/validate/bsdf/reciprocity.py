r"""The ``reciprocity`` topic: Helmholtz reciprocity f(ω_i, ω_o) = f(ω_o, ω_i).

``eval`` returns f·|cos θ_o|, so the BSDF value is eval(ω_i, ω_o)/|cos θ_o| and the check is

    eval(ω_i, ω_o) / |cos θ_o|  =  eval(ω_o, ω_i) / |cos θ_i|      (reflection pairs),

over random pairs on the upper hemisphere plus pairs at the grid's incidence angles (cos θ
down to 1e-4).  Transmission (ω_o below the surface) is not symmetric: radiance is scaled
by η² across an interface, and Mitsuba's ``TransportMode.Importance`` evaluates the adjoint
BSDF f*(ω_i, ω_o) = f(ω_o, ω_i) [Veach 1997, §5.2-5.3].  For transmission pairs the check is
therefore the adjoint form

    eval_Radiance(ω_i, ω_o) / |cos θ_o|  =  eval_Importance(ω_o, ω_i) / |cos θ_i|,

which for a physically based BTDF is the η² form f(ω_i→ω_o)/η_o² = f(ω_o→ω_i)/η_i².
A delta lobe has no eval to compare, so the adjoint is also checked on what ``sample`` returns:
with the same uniform numbers both modes draw the same ω_o, and the Radiance weight carries the
radiance scaling of the transmitted event, the Importance weight does not,

    weight_Radiance(ω_i; u)  =  weight_Importance(ω_i; u) / η²,     η = bs.eta

(η = 1 for reflection; Mitsuba's dielectric, roughdielectric and thindielectric meet it to
float32 round-off).  Only samples whose lobe and geometry agree are judged (a transmission
lobe's ω_o across the surface, a reflection lobe's on the side of ω_i): a mixture such as
``blendbsdf`` may draw a reflection lobe's ω_o across the surface, and its weight is then the
transmitting lobe's while ``bs.eta`` is the reflection's 1.  A BSDF that applies the η² scaling in both modes (as if importance were
compressed too) fails it on its transmitted samples, and light tracing (``ptracer``) carries
too much importance out of glass with it.
Tolerance: float32 round-off (roundoff.REL_TOL) plus the lane's sensitivity to an 8-ulp move
of both directions (roundoff.sensitivity); pairs with cos < 1e-4 are left out.  mitsuba3#1779.
"""

from __future__ import annotations

import mitsuba as mi
import numpy as np

from ... import probe
from . import lanes
from ..roundoff import REL_TOL, excess, rel_diff, sensitivity
from .rows import CONDITIONED, bounded_row, max_finite, worst_lane
from .topics import Row


def _pairs(opts, upper_only: bool):
    r = lanes.rng(opts.seed, "reciprocity")
    wi, _ = lanes.incident(opts.cells(), opts.n_finite // 2)
    wo = lanes.sphere(r, len(wi))
    wo[:, 2] = np.abs(wo[:, 2]) if upper_only else -np.abs(wo[:, 2])
    keep = (np.abs(wi[:, 2]) >= 1e-4) & (np.abs(wo[:, 2]) >= 1e-4)
    return wi[keep], wo[keep]


def _compare(bsdf, wi, wo, r, ctx_back=None):
    """(excess per lane, f(wi, wo), f(wo, wi) or its adjoint) with the lane's sensitivity."""
    def fwd_of(a, b):
        return probe.eval(bsdf, a, b) / np.abs(b[:, 2:3])

    def bwd_of(a, b):
        return probe.eval(bsdf, b, a, ctx_back) / np.abs(a[:, 2:3])

    fwd, bwd = fwd_of(wi, wo), bwd_of(wi, wo)
    sens = sensitivity(fwd_of, wi, wo, r, fwd) + sensitivity(bwd_of, wi, wo, r, bwd)   # errors add
    return excess(np.max(rel_diff(fwd, bwd), axis=1), sens), fwd, bwd


def reciprocity(bsdf, opts) -> list[Row]:
    r = lanes.rng(opts.seed + 1, "reciprocity")
    wi, wo = _pairs(opts, True)
    ex, fwd, bwd = _compare(bsdf, wi, wo, r)
    rows = [bounded_row("reciprocity", "f(wi, wo) = f(wo, wi), reflection", max_finite(ex), 1.0,
                 f"relative |f(wi,wo) − f(wo,wi)| over random and grid pairs on the upper "
                 f"hemisphere; {CONDITIONED}",
                 worst_lane(ex, wi, wo, {"f_wi_wo": fwd[:, 0], "f_wo_wi": bwd[:, 0]}),
                 lanes=(ex, {"wi": wi, "wo": wo}))]
    if lanes.bsdf_has(bsdf, mi.BSDFFlags.Transmission) and not lanes.delta_only(bsdf):
        wi, wo = _pairs(opts, False)
        ex, fwd, bwd = _compare(bsdf, wi, wo, r, probe.context(mode=mi.TransportMode.Importance))
        rows.append(bounded_row("reciprocity", "f(wi, wo) = f*(wo, wi), transmission (η² form)",
                         max_finite(ex), 1.0,
                         f"relative |f_Radiance(wi,wo) − f_Importance(wo,wi)| over random "
                         f"transmission pairs (the adjoint = η² form); {CONDITIONED}",
                         worst_lane(ex, wi, wo, {"f_wi_wo": fwd[:, 0], "f_adj_wo_wi": bwd[:, 0]}),
                         lanes=(ex, {"wi": wi, "wo": wo})))
    if lanes.bsdf_has(bsdf, mi.BSDFFlags.Transmission):
        row = _mode_row(bsdf, opts)
        if row is not None:
            rows.append(row)
    return rows


def _mode_row(bsdf, opts) -> Row | None:
    """weight_Radiance = weight_Importance / η² with the same u (module docstring), over
    incidences on both sides; None when no lane has a valid sample in both modes."""
    r = lanes.rng(opts.seed + 2, "reciprocity")
    wi = lanes.sphere(r, opts.n_finite // 2)
    wi = wi[np.abs(wi[:, 2]) >= 1e-4]
    u1, u2 = r.random(len(wi)), r.random((len(wi), 2))
    rad = probe.sample(bsdf, wi, u1, u2, probe.context(mode=mi.TransportMode.Radiance))
    imp = probe.sample(bsdf, wi, u1, u2, probe.context(mode=mi.TransportMode.Importance))
    valid = ((rad.pdf > 0) & (imp.pdf > 0) & np.all(np.isfinite(rad.weight), axis=1)
             & np.all(np.isfinite(imp.weight), axis=1) & np.isfinite(rad.eta) & (rad.eta > 0))
    # η = bs.eta is the event's only where the sampled lobe and the geometry agree: a mixture
    # (blendbsdf) may draw a reflection lobe's wo across the surface, where the whole
    # mixture's weight is the transmitting lobe's and bs.eta the reflection's 1
    crosses = rad.wo[:, 2] * wi[:, 2] < 0
    labelled = (rad.sampled_type & int(mi.BSDFFlags.Transmission)) != 0
    agree = crosses == labelled
    same = valid & agree & np.all(np.abs(rad.wo - imp.wo) <= 1e-5, axis=1)
    if not same.any():
        return None
    predicted = imp.weight / rad.eta[:, None] ** 2
    ex = np.where(same, np.max(rel_diff(rad.weight, predicted), axis=1) / REL_TOL, 0.0)
    k = int(np.argmax(ex))
    transmitted = same & (np.abs(rad.eta - 1.0) > 1e-6)
    return bounded_row("reciprocity", "Importance mode: weight_Importance = η² · weight_Radiance (same u)",
                       max_finite(ex[same]), 1.0,
                       f"relative |weight_Radiance − weight_Importance/η²| / REL_TOL over "
                       f"{int(same.sum())} samples drawn with the same u in both modes "
                       f"({int(transmitted.sum())} transmitted, η ≠ 1); the radiance scaling "
                       f"1/η² belongs to Radiance mode alone",
                       {"worst_wi": wi[k].tolist(), "worst_wo": rad.wo[k].tolist(),
                        "eta": float(rad.eta[k]), "weight_radiance": rad.weight[k].tolist(),
                        "weight_importance": imp.weight[k].tolist(),
                        "lanes_with_another_wo": int((valid & agree & ~same).sum()),
                        "lanes_left_out_lobe_across_surface": int((valid & ~agree).sum())},
                       lanes=(ex[same], {"wi": wi[same], "wo": rad.wo[same]}))
