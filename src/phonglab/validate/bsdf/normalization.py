r"""The ``normalization`` topic: does ``pdf`` integrate to the probability that ``sample``
returns a direction it has a density for?

For a sampler whose ``wo`` has the density ``pdf`` (solid angle) wherever it returns a
usable non-delta direction,

    Q(ω_i) = ∫_{S²} pdf(ω_i, ω_o) dω_o  =  P(ω_i) = Pr[sample(ω_i) is counted],

where a sample is counted by the χ² topic's rule applied per sample (:func:`.lanes.counted`):
not a delta lobe -- ``pdf`` has no density for a mirror or a glass interface, so a mixture
such as ``plastic`` is held to its non-delta part, whose Q and P are then both below 1 -- and
weight ≠ 0 (Mitsuba's mark of a rejected sample is weight 0), or weight 0 at a direction drawn
inside the support (``bs.pdf > 0``, ``pdf(wo) > 0``) where the BSDF is black (``eval(wo)`` = 0):
there the weight 0 is the right value, not a rejection.  In a black cell that is χ²'s
drawn-direction rule; it also covers a cell that is black in part (``pplastic`` in a
polarized variant at cos θ_i = 1e-4, where 89 % of the diffuse samples have eval 0), which
the weight rule alone would count as 30 % rejected against ∫ pdf = 1.  A sampler that
returns weight 0 where eval is not 0 still fails: those samples are not counted.

Why a topic of its own.  A pdf scaled by a constant c ≠ 1 everywhere, with ``sample`` exact
and weight = eval / pdf (so the ``weight`` and ``pdf`` identities hold, and every render is
darker by 1/c), is seen by χ² only through its normalization, where at 10⁵–10⁶ samples it has
no power for c = 1.01.  Here Q = c·P against P: a deterministic quadrature and a
count, which see 1 % at once.

Estimators.  Q by :mod:`.lobes` (``lobe_quadrature`` centred on the sampled lobe, the same rule
as ``energy``, over BOTH hemispheres for every BSDF: the pdf of a reflection-only BSDF must
vanish below the horizon, or it reports density where nothing is counted), with
:attr:`~.config.Options.normalization_nodes` per panel at both sizes (a pdf is sharper than
an albedo at grazing incidence) and the error max(|Q(n) − Q(n/2)|, |Q(n) − Q(3n/4)|)
(:func:`.lobes.integrate_with_error`: one coarser rule can agree by accident), or, where it is
larger, Q's float32 conditioning: its change when wi's norm moves by 8u (by the n/2 rule)
(:data:`phonglab.validate.roundoff.PERTURB`, the identities' perturbation).  A sampler builds its frame from
wi and draws directions whatever wi's rounding, while a pdf such as cos^p α with
cos α = ω_o · reflect(ω_i) scales by |ω_i|^p: phonglab's ``phong`` at p = 10⁴ integrates to
0.99979 at cos θ_i = 0.05 (every sample valid), the 1e-8 by which float32 ω_i misses unit
length raised to the 10⁴; an 8u move changes Q by ~1 % there, by 3e-5 at p = 30, and not
at all for a pdf that does not depend on ω_i's length (Lambert).  A cell whose lobe is a few
float32 spacings of ω wide (below :data:`.lobes.QUANTISED`) is the mean of
:data:`.lobes.COPIES` rules on shifted nodes, its error also t·s/√COPIES
(:func:`.lobes.integrate_rounded`, as in ``energy``).
Where a BSDF has several lobes, each is placed from samples of its own (each component
sampled alone, and the counted samples grouped by sampled_component and sampled_type) and the
rule, centred on the narrowest, is refined towards the others (:mod:`.lobes`): a
lobe the mixture picks with probability 10⁻⁴ is integrated as one it picks half the time.
Measured on tests/authors/narrow_broad_mixture.py (normalized Blinn-Phong, p = 2000, beside
Lambert, w_s = 2.0e-4: ``specular_reflectance`` = 1e-4), at cos θ_i = 0.15, 0.05, 0.01,
1e-4: the float64 formula integrates to 0.99999992, 0.99997369, 0.99991774, 0.99990017 (exact
lobe by lobe, (1 − w_s) + w_s·P_s with P_s from 8.4·10⁶ float64 half-vector samples,
σ ≤ 3e-8), the plugin's float32 pdf to the same within 6e-8 (Monte Carlo of pdf32 − pdf64
against the float64 mixture density, σ ≤ 1e-7), 2¹⁹ samples count 1, 0.9999657, 0.9999294,
0.9998798; the rule placed on the mixture's samples alone reads (φ_i = 2.1) 0.99983, 0.99980,
0.99980, 0.99980 with |Q16 − Q8| ≤ 3e-5 (a fail: the quadrature is wrong, not the pdf), the rule
placed per lobe reads 0.9999999, 0.9999736, 0.9999177, 0.9999001.  Where a group of counted
samples ends short of the horizon, at the smallest |ω_z| of its samples in a hemisphere with
pdf 0 halfway to the horizon, that height is an edge of the hemisphere's rule
(:func:`.lobes.support_heights`): a rough
dielectric's transmitted pdf jumps to 0 at |ω_z| = cos θ_i / η, which a panel through it
integrated 5.1e-5 too high at cos θ_i = 1e-4 with an error estimate of 2.2e-5 (:mod:`.lobes`).
P by the fraction k/N of N counted samples (:attr:`~.config.Options.normalization_samples`).
Its counting error is binomial, sqrt(p(1 − p)/N); p is the Agresti–Coull centre
(k + z²/2)/(N + z²) over N + z² trials, so that a cell where no sample is rejected
(k = N, p̂(1 − p̂) = 0: the counting error of a sampler without rejection is 0) still allows
≈ z²/(√2 N) for a rejection not yet seen, and the tolerance there is essentially the
quadrature's.  Band: z·σ + the quadrature error + :data:`.lobes.FLOOR`·max(1, Q), z the Šidák
critical value over the BSDF's statistical tests (each cell here is one of them:
:func:`.kind.statistical_tests`).  Fail when |Q − k/N| > band at any cell.

Cells: cos θ_i of :attr:`~.config.Options.energy_cos` at the azimuths of the grid (an
anisotropic BSDF differs between them), down to 1e-4 and 0, where Q and P both vanish for a
BSDF that rejects grazing light.  A BSDF whose every lobe is a delta has no density: skipped.
"""

from __future__ import annotations

import numpy as np

from ...verdict import NOT_APPLICABLE
from ... import probe, stats
from . import lanes, lobes
from ..roundoff import PERTURB
from .topics import Row


def _counts(bsdf, cells: np.ndarray, n: int, opts) -> tuple:
    """Per cell: (counted samples k, finite samples n_f, of which drawn where the BSDF is
    black, the lobes of the counted samples grouped by sampled_component and sampled_type
    where there are several groups (:func:`.lobes.group_lobes`; else ([], [])), the heights
    where each group's support ends (:func:`.lobes.support_heights`)); one cell per
    call (n lanes each), the sample values from the topic's own stream (lanes.rng).
    Non-finite samples are the finite topic's: left out of k and of n_f."""
    r = lanes.rng(opts.seed, "normalization")
    ks, totals, blacks, groups, heights = [], [], [], [], []
    for theta, phi in cells:
        wi = lanes.exact(probe.direction(theta, phi))
        s = probe.sample(bsdf, wi, r.random(n), r.random((n, 2)))
        black = lanes.black_at_wo(bsdf, wi, s)
        finite = lanes.finite_sample(s)
        k = lanes.counted(s, black, finite)
        ks.append(int(k.sum()))
        totals.append(int(finite.sum()))
        blacks.append(int((k & black).sum()))
        live = k & np.isfinite(s.pdf)
        keys = (s.sampled_component[live] << 32) | s.sampled_type[live]
        several = len(keys) > 0 and bool((keys != keys[0]).any())   # np.unique: 20x slower
        groups.append(lobes.group_lobes(s.wo[live], s.pdf[live], keys)
                      if several else ([], []))
        heights.append(lobes.support_heights(bsdf, wi, s.wo[live], keys))
    return np.array(ks), np.array(totals), blacks, groups, heights


def _conditioning(density, cells, layout, nodes, memo=None) -> np.ndarray:
    """Per cell: the largest |Q(wi·(1 ± PERTURB)) − Q(wi)| -- how far ∫pdf moves when the
    incidence direction's float32 norm moves by 8u (the identities' perturbation) -- by the
    rule of ``nodes`` per panel (a difference of two integrals by one rule: its own error
    cancels to first order, so a coarse rule measures it)."""
    integral = np.array([v for v, _ in lobes.integrate(density, cells, layout, nodes, memo)])
    moved = []
    for scale in (1.0 + PERTURB, 1.0 - PERTURB):
        def scaled(wi, wo, scale=scale):
            return density(wi * scale, wo)
        moved.append(np.array([v for v, _ in lobes.integrate(scaled, cells, layout, nodes,
                                                             memo)]))
    return np.max(np.abs(np.array(moved) - integral), axis=0)


def counting_error(k: np.ndarray, n: int, z: float) -> np.ndarray:
    """Binomial standard error of k/n with p the Agresti–Coull centre (k + z²/2)/(n + z²)."""
    p = (k + 0.5 * z * z) / (n + z * z)
    return np.sqrt(p * (1.0 - p) / (n + z * z))


def normalization(bsdf, opts, m_tests: int) -> list[Row]:
    name = "∫ pdf dω_o = P(sample counted)"
    if lanes.delta_only(bsdf):
        return [Row("normalization", name, None, None, None, None, "skipped",
                    "every lobe is a delta: pdf has no density to integrate",
                    {NOT_APPLICABLE: True})]
    cells = opts.cells(opts.energy_cos)
    n = opts.normalization_samples
    k, n_f, blacks, groups, heights = _counts(bsdf, cells, n, opts)
    layout = lobes.layout(bsdf, cells, lanes.STREAMS.int_seed(opts.seed, "normalization"),
                          whole_sphere=True, components=True, extra=groups, heights=heights)

    def density(wi, wo):
        return probe.pdf(bsdf, wi, wo)

    nodes = opts.normalization_nodes
    memo: dict = {}                 # the rules' nodes, built once for both
    integral, qerr, nonfinite = lobes.integrate_with_error(density, cells, layout, nodes, memo)
    qerr = np.maximum(qerr, _conditioning(density, cells, layout, max(1, nodes // 2), memo))
    integral, qerr, narrow = lobes.with_rounding(density, cells, layout, nodes, integral, qerr,
                                                 m_tests)
    z = stats.z_critical(stats.ALPHA, m_tests)
    n_f = np.maximum(n_f, 1)
    p_hat = k / n_f
    sigma = counting_error(k, n_f, z)
    band = z * sigma + qerr + lobes.FLOOR * np.maximum(1.0, integral)
    dev = np.abs(integral - p_hat)
    bad = dev > band
    j = int(np.argmax(dev / band))
    theta_deg = np.degrees(cells[:, 0])
    where = ", ".join(f"θ_i = {theta_deg[i]:.1f}° φ = {cells[i, 1]:.2f} (∫pdf {integral[i]:.5g}"
                      f" vs {p_hat[i]:.5g})" for i in np.flatnonzero(bad))
    refined = sum(bool(lobes.parts_of(entry)[2] or lobes.parts_of(entry)[3])
                  for entry in layout)
    ended = sum(bool(lobes.parts_of(entry)[4] or lobes.parts_of(entry)[5]) for entry in layout)
    reason = (f"∫ pdf over the sphere by lobe-centred Gauss-Legendre ({nodes} nodes/panel, "
              f"error max |Q{nodes} − Q{nodes // 2}|, |Q{nodes} − Q{3 * nodes // 4}|"
              + (f"; {refined} cells with several lobes, each placed from its own samples: "
                 f"the rule centred on the narrowest, graded towards the others"
                 if refined else "")
              + (f"; {ended} cells with a panel edge where the support ends short of the "
                 f"horizon (the smallest |ω_z| of a lobe's samples, pdf 0 halfway to the "
                 f"horizon)" if ended else "")
              + (f"; {int(narrow.sum())} cells with a lobe narrower than "
                 f"{lobes.QUANTISED:.1e} rad: mean of {lobes.COPIES} rules on shifted nodes, "
                 f"error t·s/√{lobes.COPIES} if larger" if narrow.any() else "")
              + ") against "
              f"the fraction of {n} samples with weight ≠ 0 (or 0 where eval is 0) and not "
              f"delta; band z·σ + "
              f"quadrature error, σ binomial (Agresti–Coull), z = {z:.3f} (Šidák over "
              f"{m_tests} tests) at {len(cells)} incidence cells"
              + (f"; NOT NORMALIZED at {where}" if bad.any() else ""))
    details = {"theta_deg": theta_deg.tolist(), "phi": cells[:, 1].tolist(),
               "integral": integral.tolist(), "counted": p_hat.tolist(),
               "samples": n, "finite_samples": n_f.tolist(), "sigma": sigma.tolist(),
               "quadrature_error": qerr.tolist(),
               "band": band.tolist(), "black_samples": blacks,
               "nonfinite_nodes": nonfinite}
    row = Row("normalization", name, float(integral[j]), float(p_hat[j]), float(sigma[j]),
              float(band[j]), "fail" if bad.any() else "pass", reason, details)
    if bad.any():      # the failing cells' incidence, for a finding's signature
        row.failing_lanes = {"wi": np.array([lanes.exact(probe.direction(t, p))
                                             for t, p in cells[bad]])}
    return [row]

