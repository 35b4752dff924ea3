r"""The statistics of every check, benchmark and test: one home for the critical values.

Every statistical comparison in phonglab has the form "|measured − expected| <= c · stderr"
with the critical value c chosen for a significance level α, corrected for the number of
comparisons made together:

* **Šidák** [Z. Šidák, "Rectangular confidence regions for the means of multivariate normal
  distributions", JASA 62 (1967)]: m independent tests each at level
  α' = 1 − (1 − α)^{1/m} keep the family-wise error rate at exactly α
  (:func:`sidak`); :func:`z_critical` and :func:`t_critical` are the two-sided normal and
  Student-t quantiles at that level.
* **Holm** [S. Holm, "A simple sequentially rejective multiple test procedure", Scand. J.
  Statist. 6 (1979)]: step-down adjusted p-values, valid under any dependence
  (:func:`holm`), used for per-pixel tests whose pixels a reconstruction filter correlates.
* **Welch** [B. L. Welch, Biometrika 34 (1947)]: the two-sample t-test with unequal
  variances and the Welch–Satterthwaite degrees of freedom (:func:`welch_pvalues`).
* The distributions are ``scipy.special``'s (``ndtr``/``ndtri`` for the normal, ``stdtr``/
  ``stdtrit`` for Student's t, ``chdtrc`` for the χ² tail), the functions ``scipy.stats``
  evaluates underneath: importing ``scipy.stats`` cost every validate process 0.69 s of its
  0.81 s of imports, ``scipy.special`` 0.05 s.
* **Pearson's χ²** [K. Pearson, Phil. Mag. 50 (1900)] of a histogram against expected counts
  (:func:`pearson_chi2`), with Mitsuba's pooling of sparse cells (``mitsuba::math::chi2``,
  include/mitsuba/core/math.h): cells sorted by expected count, those below 5 summed in that
  order into groups that each exceed 5 (a last group that does not is dropped), dof = cells
  + groups − 1, p = P(χ²_dof ≥ statistic).  A sample in a cell of expected count 0 makes
  p = 0: the BSDF and phase-function topics re-integrate such slivers first
  (:mod:`phonglab.validate.sphere_bins`).  ``pooling="one"`` instead sums every sparse cell,
  empty-expected ones included, into one cell (merged into the smallest remaining cell when
  that pool is itself below 5): the emitters' (cos θ, φ) lattice has no re-integration, so a
  sample in a bin whose quadrature found 0 is pooled, not impossible.

:data:`ALPHA` = 0.01 is the project's family-wise level: a correct plugin fails a whole
check run, or a test, at most 1 % of the time.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import special

#: Family-wise significance level of every statistical check, benchmark verdict and test.
ALPHA = 0.01


def sidak(alpha: float, m: int) -> float:
    """Per-test level keeping the family-wise error rate at ``alpha`` over m independent tests."""
    return 1.0 - (1.0 - alpha) ** (1.0 / max(1, int(m)))


def z_critical(alpha: float = ALPHA, m: int = 1) -> float:
    """Two-sided standard-normal quantile at the Šidák level of m tests: P(|Z| > z) = sidak(α, m)."""
    return float(-special.ndtri(sidak(alpha, m) / 2.0))


def t_critical(dof: float, alpha: float = ALPHA, m: int = 1) -> float:
    """Two-sided Student-t quantile with ``dof`` degrees of freedom at the Šidák level of m tests."""
    return float(-special.stdtrit(dof, sidak(alpha, m) / 2.0))


def two_sided_p(z) -> np.ndarray | float:
    """Two-sided p-value 2(1 − Φ(|z|)) of a standard-normal statistic."""
    p = 2.0 * special.ndtr(-np.abs(z))
    return float(p) if np.ndim(p) == 0 else p


def holm(pvalues: np.ndarray) -> np.ndarray:
    """Holm's step-down adjusted p-values: max_{j<=k} min(1, (m − j + 1) p_(j)), same shape."""
    p = np.asarray(pvalues, dtype=np.float64).ravel()
    m = p.size
    order = np.argsort(p)
    adj = np.minimum(1.0, (m - np.arange(m)) * p[order])
    adj = np.maximum.accumulate(adj)
    out = np.empty(m)
    out[order] = adj
    return out.reshape(np.shape(pvalues))


def welch_pvalues(m1, se1, m2, se2, passes1: int, passes2: int) -> tuple[np.ndarray, np.ndarray]:
    """Two-sided Welch t-test p-values of per-pixel means with standard errors se1, se2.

    t = (m1 − m2)/√(se1² + se2²), Welch–Satterthwaite dof
    ν = (se1² + se2²)² / (se1⁴/(k1 − 1) + se2⁴/(k2 − 1)) with k the number of passes.
    Pixels with zero variance in both renders get p = 1 when equal, 0 otherwise.

    Returns:
        (p-values, t statistics), each of the shape of the inputs.
    """
    v1, v2 = np.asarray(se1, np.float64) ** 2, np.asarray(se2, np.float64) ** 2
    diff = np.asarray(m1, np.float64) - np.asarray(m2, np.float64)
    v = v1 + v2
    zero = v <= 0
    vs = np.where(zero, 1.0, v)
    t = diff / np.sqrt(vs)
    dof = vs * vs / np.maximum(v1 * v1 / (passes1 - 1) + v2 * v2 / (passes2 - 1), 1e-300)
    p = 2.0 * special.stdtr(np.maximum(dof, 1.0), -np.abs(t))
    p = np.where(zero, np.where(diff == 0, 1.0, 0.0), p)
    return p, np.where(zero, 0.0, t)


#: Expected count below which :func:`pearson_chi2` pools a cell with its neighbours in order.
POOL_BELOW = 5.0


@dataclass(frozen=True)
class PearsonChi2:
    """The result of :func:`pearson_chi2`."""

    statistic: float
    dof: int
    p_value: float               #: 0 when a cell of expected count 0 holds observations
    pooled_in: int               #: cells pooled (expected count < POOL_BELOW, not both 0)
    pooled_out: int              #: groups they formed
    impossible: int              #: observations in cells whose expected count is 0
    residual: np.ndarray         #: (obs − exp)/√exp per cell, NaN where pooled or empty


def pearson_chi2(observed, expected, pool_below: float = POOL_BELOW,
                 pooling: str = "running") -> PearsonChi2:
    """Pearson's χ² of ``observed`` counts against ``expected`` ones (same shape).

    ``pooling="running"`` pools as ``mitsuba::math::chi2``: cells sorted by expected count
    (stable), cells with both counts 0 skipped, a cell of expected count < ``pool_below``
    added to a running group that counts as one cell once its expected count exceeds
    ``pool_below``.  ``pooling="one"`` sums every cell below ``pool_below`` into one cell (see
    the module docstring).  The residual map has the shape of the inputs: (obs − exp)/√exp for
    every cell tested on its own.
    """
    obs = np.asarray(observed, np.float64)
    exp = np.asarray(expected, np.float64)
    if pooling == "one":
        return _one_pool(obs, exp, pool_below)
    if pooling != "running":
        raise ValueError(f"pooling must be 'running' or 'one', not {pooling!r}")
    o, e = obs.ravel(), exp.ravel()
    order = np.argsort(e, kind="stable")
    o, e = o[order], e[order]
    high = e >= pool_below
    stat = float(np.sum((o[high] - e[high]) ** 2 / e[high]))
    dof = int(np.count_nonzero(high))
    low = ~high & ((o != 0) | (e != 0))
    pooled_in, pooled_out = int(np.count_nonzero(low)), 0
    po = pe = 0.0
    for ok, ek in zip(o[low], e[low]):
        po, pe = po + ok, pe + ek
        if pe > pool_below:
            stat += (po - pe) ** 2 / pe
            po = pe = 0.0
            pooled_out += 1
            dof += 1
    dof -= 1
    impossible = float(np.sum(obs[exp == 0]))
    p = float(special.chdtrc(dof, stat)) if dof >= 1 and impossible == 0 else 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        residual = np.where(exp >= pool_below, (obs - exp) / np.sqrt(exp), np.nan)
    return PearsonChi2(stat, dof, p, pooled_in, pooled_out, int(impossible), residual)

def _one_pool(obs: np.ndarray, exp: np.ndarray, pool_below: float) -> PearsonChi2:
    """:func:`pearson_chi2` with every cell of expected count < ``pool_below`` in one pool."""
    o, e = obs.ravel(), exp.ravel()
    low = e < pool_below
    cells_o, cells_e = list(o[~low]), list(e[~low])
    po, pe = float(o[low].sum()), float(e[low].sum())
    pooled_in = int(np.count_nonzero(low & ((o != 0) | (e != 0))))
    if pe >= pool_below or not cells_e:
        cells_o.append(po)
        cells_e.append(pe)
    elif po > 0 or pe > 0:
        k = int(np.argmin(cells_e))
        cells_o[k] += po
        cells_e[k] += pe
    co, ce = np.array(cells_o), np.array(cells_e)
    impossible = float(np.sum(co[ce <= 0]))
    keep = ce > 0
    if impossible > 0:
        stat, dof, p = float("inf"), len(ce) - 1, 0.0
    else:
        stat, dof = float(np.sum((co[keep] - ce[keep]) ** 2 / ce[keep])), max(1, int(keep.sum()) - 1)
        p = float(special.chdtrc(dof, stat))
    with np.errstate(divide="ignore", invalid="ignore"):
        residual = np.where(exp >= pool_below, (obs - exp) / np.sqrt(exp), np.nan)
    return PearsonChi2(stat, dof, p, pooled_in, int(pooled_in > 0), int(impossible), residual)

