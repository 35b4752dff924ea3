r"""The ``energy`` topic: directional albedo a(θ_i) = ∫ f cos θ_o dω_o ≤ 1, with its error band.

Estimators (chosen so that a sampling defect does not leak into this topic):

* the non-delta part is a deterministic quadrature of ``eval`` (:mod:`.lobes`:
  :func:`phonglab.physics.quadrature.lobe_quadrature` over the reflection hemisphere, and for a
  transmitting BSDF the same rule mirrored into the lower hemisphere).  Each rule is centred on
  the lobe's peak (the mean direction of the 10 % most probable samples, so a normal map or a
  rotated anisotropy that moves the lobe away from the mirror direction is followed) and
  covers the whole circle around it; the BSDF's own samples only place the panels, the value
  is Σ w_k eval(ω_k), independent of ``sample``.
  Its error is estimated as |Q(n) − Q(n/2)| (Gauss-Legendre converges fast, so Q(n) is
  far closer than that).  A lobe a few float32 spacings of ω wide (below
  :data:`.lobes.QUANTISED`; a rough dielectric between nearly equal indices, α|η − 1| down to
  ~10⁻⁶ rad) sees every node at its float32 rounding, an error that Q(n/2) does not reveal:
  such a cell is the mean of :data:`.lobes.COPIES` rules on shifted nodes
  (:func:`.lobes.integrate_rounded`), its error the larger of |Q(n) − Q(n/2)| and t·s/√COPIES
  (Student's t at the topic's level, COPIES − 1 degrees of freedom);
* a delta lobe (mirror, glass) has no eval: its part is the mean of the delta samples'
  weights (times their indicator), whose standard error s gives the band z·s with z the
  Šidák critical value over the BSDF's statistical tests.  For a smooth ``dielectric`` this is
  R + T, which must be 1.

All of it in ``TransportMode.Importance`` (ω_i is then the light's direction, and the albedo
the fraction of the incident flux that is scattered; Radiance mode scales transmission by
1/η², which is not an energy balance).  Fail when a(θ_i) > 1 + band at any cell; a loss
below 1 is reported in the reason (single-scattering microfacet models lose energy at
high roughness and grazing incidence by design [Heitz et al. 2016], mitsuba3#1155).
"""

from __future__ import annotations

import math

import mitsuba as mi
import numpy as np

from ... import probe, stats
from . import lanes, lobes
from .topics import Row

def _delta_part(bsdf, thetas, opts, ctx):
    """(mean, standard error) per cell of weight · 1{delta sample}."""
    n = opts.energy_samples
    wi, _ = lanes.incident(np.column_stack([thetas, np.zeros_like(thetas)]), n)
    s = probe.sample_random(bsdf, wi, len(wi), seed=lanes.STREAMS.int_seed(opts.seed, "energy", 1),
                            ctx=ctx)
    x = np.where(lanes.delta_mask(s.sampled_type), s.weight.mean(axis=1), 0.0)
    x = np.where(np.isfinite(x), x, 0.0).reshape(len(thetas), n)
    return x.mean(axis=1), x.std(axis=1, ddof=1) / math.sqrt(n)


#: Incidence angles (degrees) of the lobe slices the HTML report plots.
SLICE_THETAS = (0.0, 30.0, 60.0, 80.0)


def lobe_slices(bsdf) -> dict:
    """eval (f cos θ_o, channel mean) and pdf in the plane of incidence, θ_o ∈ [−180°, 180°].

    ω_o = (sin t, 0, cos t): t < 0 is the mirror side, |t| > 90° the transmission side.
    """
    t = np.radians(np.linspace(-180.0, 180.0, 361))
    wo = lanes.exact(np.column_stack([np.sin(t), np.zeros_like(t), np.cos(t)]))
    out = {"theta_o_deg": np.degrees(t).tolist(), "slices": []}
    for theta in SLICE_THETAS:
        wi = probe.direction(math.radians(theta))
        ev = probe.eval(bsdf, wi, wo).mean(axis=1)
        pd = probe.pdf(bsdf, wi, wo)
        out["slices"].append({"theta_i_deg": theta, "eval": np.nan_to_num(ev).tolist(),
                              "pdf": np.nan_to_num(pd).tolist()})
    return out


def energy(bsdf, opts, m_tests: int) -> list[Row]:
    thetas = np.arccos(np.clip(np.array(opts.energy_cos, dtype=np.float64), 0.0, 1.0))
    ctx = probe.context(mode=mi.TransportMode.Importance)
    has_delta = lanes.bsdf_has(bsdf, int(mi.BSDFFlags.Delta) | int(mi.BSDFFlags.Delta1D))
    only_delta = lanes.delta_only(bsdf)
    z = stats.z_critical(stats.ALPHA, m_tests)
    a = np.zeros(len(thetas))
    qerr, se, nonfinite = np.zeros(len(thetas)), np.zeros(len(thetas)), 0
    narrow = np.zeros(len(thetas), bool)
    if not only_delta:
        cells = np.column_stack([thetas, np.zeros_like(thetas)])
        layout = lobes.layout(bsdf, cells, lanes.STREAMS.int_seed(opts.seed, "energy"),
                              samples=opts.energy_layout_samples)

        def albedo(wi, wo):
            return probe.eval(bsdf, wi, wo, ctx).mean(axis=1)

        q = lobes.integrate(albedo, cells, layout, opts.energy_nodes)
        q_half = lobes.integrate(albedo, cells, layout, opts.energy_nodes // 2)
        a += np.array([v for v, _ in q])
        qerr = np.abs(a - np.array([v for v, _ in q_half]))
        nonfinite = sum(c for _, c in q)
        a, qerr, narrow = lobes.with_rounding(albedo, cells, layout, opts.energy_nodes, a, qerr,
                                              m_tests)
    if has_delta:
        mean, se = _delta_part(bsdf, thetas, opts, ctx)
        a += mean
    band = z * se + qerr + lobes.FLOOR * np.maximum(1.0, a)
    over = a > 1.0 + band
    k = int(np.argmax(a - band))
    method = ("mean delta-sample weight (R + T for a smooth dielectric)" if only_delta else
              f"Gauss-Legendre quadrature of eval ({opts.energy_nodes} nodes/panel, error "
              f"|Q{opts.energy_nodes} − Q{opts.energy_nodes // 2}|"
              + (f"; a lobe narrower than {lobes.QUANTISED:.1e} rad at θ_i = "
                 + ", ".join(f"{math.degrees(t):.1f}°" for t in thetas[narrow])
                 + f": mean of {lobes.COPIES} rules on shifted nodes, error t·s/√"
                 f"{lobes.COPIES} if larger" if narrow.any() else "") + ")"
              + (" + mean delta-sample weight" if has_delta else ""))
    lit = np.cos(thetas) >= 0.01
    loss = 1.0 - a[lit]
    loss_note = (f"loss below 1: {loss.min():.3g} to {loss.max():.3g} for cos θ_i ≥ 0.01 "
                 f"(expected for absorbing materials and for single-scattering microfacet "
                 f"models at high roughness/grazing incidence)" if lit.any() else "")
    reason = (f"directional albedo (TransportMode.Importance) by {method}; band z·stderr + "
              f"quadrature error, z = {z:.3f} (Šidák over {m_tests} tests); "
              + ("ABOVE 1 at θ_i = " + ", ".join(f"{math.degrees(t):.1f}°" for t in thetas[over])
                 if over.any() else loss_note))
    details = {"relation": "<=", "theta_deg": np.degrees(thetas).tolist(), "albedo": a.tolist(),
               "band": band.tolist(), "stderr": np.asarray(se).tolist(),
               "quadrature_error": np.asarray(qerr).tolist(), "nonfinite_nodes": nonfinite,
               "lobes": lobe_slices(bsdf)}
    return [Row("energy", "directional albedo ≤ 1", float(a[k]), 1.0, float(np.asarray(se)[k]),
                float(band[k]), "fail" if over.any() else "pass", reason, details)]
