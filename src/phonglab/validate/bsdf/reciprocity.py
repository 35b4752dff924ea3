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
Tolerance: float32 round-off (roundoff.REL_TOL) plus the lane's sensitivity to an 8-ulp move
of both directions (roundoff.sensitivity); pairs with cos < 1e-4 are left out.  mitsuba3#1779.
"""

from __future__ import annotations

import mitsuba as mi
import numpy as np

from ... import probe
from . import lanes
from ..roundoff import excess, rel_diff, sensitivity
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
    return rows
