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
Tolerance: float32 round-off (config.REL_TOL); pairs with cos < 1e-4 are left out (the
division by the cosine amplifies round-off there).  mitsuba3#1779.
"""

from __future__ import annotations

import mitsuba as mi
import numpy as np

from .. import probe
from . import lanes
from .config import REL_TOL, rel_diff
from .identities import _max, _row, _worst
from .report import Row


def _pairs(opts, upper_only: bool):
    r = lanes.rng(opts.seed, "reciprocity")
    wi, _ = lanes.incident(opts.cells(), opts.n_finite // 2)
    wo = lanes.sphere(r, len(wi))
    wo[:, 2] = np.abs(wo[:, 2]) if upper_only else -np.abs(wo[:, 2])
    keep = (np.abs(wi[:, 2]) >= 1e-4) & (np.abs(wo[:, 2]) >= 1e-4)
    return wi[keep], wo[keep]


def reciprocity(bsdf, opts) -> list[Row]:
    rows = []
    wi, wo = _pairs(opts, True)
    fwd = probe.eval(bsdf, wi, wo) / np.abs(wo[:, 2:3])
    bwd = probe.eval(bsdf, wo, wi) / np.abs(wi[:, 2:3])
    rel = np.max(rel_diff(fwd, bwd), axis=1)
    rows.append(_row("reciprocity", "f(wi, wo) = f(wo, wi), reflection", _max(rel), REL_TOL,
                     "max relative |f(wi,wo) − f(wo,wi)| over random and grid pairs on the "
                     "upper hemisphere; float32 round-off tolerance 2^-10",
                     _worst(rel, wi, wo, {"f_wi_wo": fwd[:, 0], "f_wo_wi": bwd[:, 0]})))
    if lanes.bsdf_has(bsdf, mi.BSDFFlags.Transmission) and not lanes.delta_only(bsdf):
        wi, wo = _pairs(opts, False)
        fwd = probe.eval(bsdf, wi, wo) / np.abs(wo[:, 2:3])
        imp = probe.context(mode=mi.TransportMode.Importance)
        bwd = probe.eval(bsdf, wo, wi, imp) / np.abs(wi[:, 2:3])
        rel = np.max(rel_diff(fwd, bwd), axis=1)
        rows.append(_row("reciprocity", "f(wi, wo) = f*(wo, wi), transmission (η² form)",
                         _max(rel), REL_TOL,
                         "max relative |f_Radiance(wi,wo) − f_Importance(wo,wi)| over random "
                         "transmission pairs (the adjoint = η² form); float32 round-off "
                         "tolerance 2^-10",
                         _worst(rel, wi, wo, {"f_wi_wo": fwd[:, 0], "f_adj_wo_wi": bwd[:, 0]})))
    return rows
