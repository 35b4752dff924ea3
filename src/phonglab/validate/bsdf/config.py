r"""The validator's sizes, grids and round-off tolerances (one place, quick and default).

Incidence grid.  Cells are (θ_i, φ_i) with cos θ_i in :attr:`Options.cos_grid` -- normal
incidence, the interior, grazing cos θ_i = 1e-4 and exactly 0 -- at the azimuths
:attr:`Options.phi_grid` (an anisotropic BSDF differs between them).  Every topic's lanes for
all cells go to Mitsuba in ONE call (``wi`` is an (N, 3) array, i.e. an opaque kernel input),
so a kernel is compiled once per query, not once per angle.

Round-off tolerances and the conditioning of the identities: :mod:`phonglab.validate.roundoff`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import drjit as dr
import mitsuba as mi
import numpy as np



@dataclass
class Options:
    """Sizes of one validation run; :func:`options` builds the default or quick ones."""

    quick: bool = False
    seed: int = 0
    cos_grid: tuple = (1.0, 0.9, 0.7, 0.5, 0.3, 0.1, 0.02, 1e-4, 0.0)
    phi_grid: tuple = (0.0, 2.1)
    n_identity: int = 4096            #: sample() lanes per cell for weight/pdf/component
    n_finite: int = 2048              #: random wo per cell for finite/eval_pdf/reciprocity
    #: χ² incidences avoid the pole: the (φ, cos θ) bins of sphere_bins, so a narrow lobe
    #: at θ ≈ 0 (or 180°) falls within one row of bins, all meeting at the pole.
    chi2_cos: tuple = (0.95, 0.8, 0.7071, 0.5, 0.2)
    chi2_phi: tuple = (0.0, 1.0)
    chi2_samples: int = 1_000_000
    chi2_res: int = 101               #: rows of cos θ bins (odd); ⌊res/2⌋ columns of φ
    #: Gauss-Legendre nodes per panel and axis of a bin's pdf integral: the first level, and the
    #: cap of the per-bin refinement k, 2k, 4k, ... (sphere_bins.expected_counts; 2 × 2 panels).
    chi2_ires: int = 2
    chi2_ires_max: int = 64
    energy_cos: tuple = (1.0, 0.95, 0.85, 0.7, 0.5, 0.3, 0.15, 0.05, 0.01, 1e-4, 0.0)
    energy_nodes: int = 16            #: Gauss-Legendre nodes per panel (error from n vs n/2)
    energy_samples: int = 100_000     #: samples per cell for the delta lobes' albedo
    #: samples per cell counted by the normalization topic (its cells are energy_cos × phi_grid);
    #: binomial error ≤ 0.5/√N, 7e-4 here
    normalization_samples: int = 1 << 19
    normalization_nodes: int = 16     #: its Gauss-Legendre nodes per panel, at both sizes
    null_samples: int = 1 << 16       #: samples per cell of the Null lobe (eval_null_transmission)
    energy_layout_samples: int = 2048  #: samples per cell that place energy's panels (lobes.layout)
    gradient_lanes: int = 4096
    cost_lanes: int = 1 << 18
    cost_repeats: int = 5
    topics: tuple = field(default_factory=tuple)
    #: the :class:`~phonglab.settings.Loaded` under validation (its spec and ``--plugin``
    #: files), set by :func:`phonglab.validate.core.run`: the ``intensity`` topic loads the
    #: BSDF again in the unpolarized variant
    source: Any = None

    def cells(self, cos=None, phi=None) -> np.ndarray:
        """(M, 2) array of (θ_i, φ_i) cells; normal incidence once (its azimuth is moot)."""
        cos = self.cos_grid if cos is None else cos
        phi = self.phi_grid if phi is None else phi
        out = []
        for c in cos:
            theta = math.acos(min(1.0, max(0.0, c)))
            for p in (phi[:1] if c >= 1.0 else phi):
                out.append((theta, p))
        return np.array(out)


def options(quick: bool = False, seed: int = 0, topics=(), scalar: bool | None = None) -> Options:
    """The default sizes (≤ 60 s per BSDF on 2 cores) or the quick ones (≤ 10 s).

    ``scalar``: the sizes of a scalar variant (default: whether the active variant is one).
    There a Dr.Jit value holds one lane and the probe calls the BSDF once per lane from Python
    (~40 µs a call, about 150× a JIT lane), so the same grids of incidence cells get fewer
    lanes per cell (:data:`SCALAR`).  What that costs: the identities see 8× fewer random lanes
    per cell (still every cell, every edge sample value and special direction); χ² tests
    N = 4 000 samples in 13 × 6 bins at --quick (20 000 in 21 × 10 at default) instead of
    200 000 in 61 × 30 (10⁶ in 101 × 50).  Its power: a sampled density off by a factor 1 + r
    over a region holding a fraction P of the samples is rejected half the time when the
    noncentrality N·r²·P reaches ≈ χ²-critical − dof, i.e. r²P ≳ 0.007 at --quick (r = 30 %
    over 8 % of the samples) and 0.0026 at default, against 0.0006 and 0.0002 in JIT
    variants; a uniform-for-cosine sampler (tests/defects/pdf_mismatch.py) is still rejected
    at p ≈ 0.  The energy and normalization quadratures use fewer nodes (--quick: 4 and 2 per
    panel, on 3 cos θ_i), so their bands, from |Q(n) − Q(n/2)|, are wider (phong's
    normalization band 0.044 at --quick against 0.018 with 4 nodes); the normalization counts
    2 048 samples per cell (--quick).  Measured: phonglab's phong --quick took 13.1 s in
    scalar_rgb with 4 and 6 nodes, 8.7 s with 2 and 4.
    """
    if scalar is None:
        scalar = mi.variant() is not None and not dr.is_jit_v(mi.Float)
    if not quick:
        opts = Options(seed=seed, topics=tuple(topics))
    else:
        opts = Options(quick=True, seed=seed, topics=tuple(topics),
                       cos_grid=(1.0, 0.6, 0.2, 1e-4, 0.0), phi_grid=(0.0, 2.1),
                       n_identity=1024, n_finite=512,
                       chi2_cos=(0.8, 0.5, 0.2), chi2_phi=(0.0,), chi2_samples=200_000,
                       chi2_res=61,
                       energy_cos=(1.0, 0.7, 0.3, 0.05, 1e-4), energy_nodes=10,
                       energy_samples=20_000, normalization_samples=1 << 17,
                       null_samples=1 << 14, gradient_lanes=1024, cost_lanes=1 << 16,
                       cost_repeats=3)
    return replace(opts, **SCALAR["quick" if quick else "default"]) if scalar else opts


#: Sizes that replace the JIT ones in scalar variants (see :func:`options`).
SCALAR = {
    "default": dict(n_identity=512, n_finite=256, chi2_samples=20_000, chi2_res=21,
                    chi2_ires=1, chi2_ires_max=32,
                    energy_nodes=10, energy_samples=5_000, normalization_samples=1 << 15,
                    normalization_nodes=8, null_samples=1 << 13, cost_lanes=2048,
                    cost_repeats=3),
    "quick": dict(n_identity=128, n_finite=64, chi2_samples=4_000, chi2_res=13, chi2_ires=1,
                  chi2_ires_max=16,
                  energy_cos=(1.0, 0.3, 1e-4), energy_nodes=4, energy_samples=2_000,
                  energy_layout_samples=512, normalization_samples=1 << 11,
                  normalization_nodes=2, null_samples=1 << 11,
                  cost_lanes=512, cost_repeats=1),
}
