r"""The ``chi2`` topic's domain: (φ, cos θ) bins over the sphere, the histogram of sampled
directions in them, and the expected count per bin, N·∫pdf, by a lobe-adaptive quadrature.

Bins.  Those of ``mi.chi2.SphericalDomain`` with ``mi.chi2.ChiSquareTest(res=R)``
(mitsuba/python/chi2.py): the parameter (x, y) = (φ, −cos θ) ∈ [−π, π] × [−1, 1] (the map
has unit Jacobian, dω = dφ d(cos θ)), cut into ⌊R/2⌋ equal φ columns and R equal rows, row 0
holding cos θ = 1.  A direction falls in column ⌊(φ + π)/(2π)·⌊R/2⌋⌋ and row
⌊(1 − cos θ)/2·R⌋, both clipped to the grid (as mi.chi2 does).  R is odd, so the horizon
cos θ = 0 is the midpoint of the middle row.

Expected counts.  Per bin, a tensor Gauss-Legendre rule on 2 × 2 panels (the bin halved in
each axis, so the horizon -- where every BSDF's pdf may have a kink or a jump -- is a panel
edge, never inside a panel) with k nodes per panel and axis, k = k₀, 2k₀, 4k₀, ... up to
``k_max``.  A bin is done at the first k where its integrals I_k and I_{k/2} differ by at most

    τ(E) = max(ε E / √max(E, 5),  ε √5 / B,  ρ E),        ε = :data:`EPS` = 0.02,
                                                          ρ = :data:`FLOAT32_REL` = 10⁻⁴,

with E = N·I_k its expected count and B the number of bins, and I_k is its value; a bin not
done at ``k_max`` keeps I_{k_max} and is counted (``integration.unconverged`` in the cell's
record, with the largest |I_k − I_{k/2}| there).  |I_k − I_{k/2}| bounds the error of the
coarser rule; Gauss-Legendre converges geometrically on an analytic lobe, so I_k is far
closer.  Only the bins whose pdf varies on a scale finer than the nodes are refined: a lobe
of width w needs nodes ≲ w apart, a smooth diffuse pdf is done at k = 2k₀ everywhere.

Error bound against the χ² statistic.  A bin tested on its own (E ≥ 5) is off by δ ≤ ε√E,
so the statistic Σ(O − E)²/E moves by at most Σδ²/E ≤ ε²K in its mean and by a term of
standard deviation ≤ 2ε√K (K bins), against its own standard deviation √(2 dof) ≈ √(2K).
With ε = 0.02 that is ≤ 4·10⁻⁴ K and ≤ 0.04√K: at K = 5050 (the default 101-row grid),
2.0 and 2.8 against 100, i.e. a change of the p-value in its third digit -- not enough to pass
a wrong sampler or fail a right one.  A pooled group of expected count E_g ∈ (5, 10] is off by
≤ ε E_g/√5 + ε√5 (the floor summed over all bins) ≲ 2ε√E_g, the same order.  The ρE term
is the float32 floor of the pdf itself: a lobe cos^p α of a float32 cos α moves by p·2⁻²⁴ per
ulp (6·10⁻⁴ at p = 10⁴), so its integral is a staircase's, not defined much better than 10⁻⁴
relative; it binds only where E > (ε/ρ)² = 40 000, and moves the statistic by at most
Σρ²E = ρ²N = 0.01 at N = 10⁶.
"""

from __future__ import annotations

import math

import numpy as np

#: Fraction of a bin's Poisson standard deviation its pdf integral may be off by (see above).
EPS = 0.02
#: Relative accuracy of a bin's integral beyond which a float32 pdf has no more to give.
FLOAT32_REL = 1e-4
#: Pooling threshold of the χ² test (stats.POOL_BELOW), in the floor of the tolerance.
POOL = 5.0
#: Pdf evaluations per probe call (memory bound of one kernel launch).
CHUNK = 1 << 21


class Grid:
    """mi.chi2.SphericalDomain's bins for ``res`` rows: (rows, cols) = (res, ⌊res/2⌋)."""

    def __init__(self, res: int):
        self.rows, self.cols = int(res), max(int(res) // 2, 1)

    @property
    def shape(self) -> tuple[int, int]:
        return self.rows, self.cols

    def index(self, wo: np.ndarray) -> np.ndarray:
        """Flat bin index (row · cols + col) of each direction (N, 3)."""
        phi = np.arctan2(wo[:, 1], wo[:, 0])
        col = np.clip(np.floor((phi + math.pi) / (2 * math.pi) * self.cols), 0, self.cols - 1)
        row = np.clip(np.floor((1.0 - wo[:, 2]) / 2.0 * self.rows), 0, self.rows - 1)
        return (row * self.cols + col).astype(np.int64)

    def histogram(self, wo: np.ndarray, index: np.ndarray | None = None) -> np.ndarray:
        """Counts (rows, cols) of the directions (N, 3) (``index``: their :meth:`index`,
        when already computed)."""
        index = self.index(wo) if index is None else index
        counts = np.bincount(index, minlength=self.rows * self.cols)
        return counts.reshape(self.shape).astype(np.float64)

    def ranges(self, flat: int) -> dict:
        """The θ_o and φ_o ranges (degrees) of bin ``flat``."""
        row, col = divmod(int(flat), self.cols)
        cos_hi, cos_lo = 1.0 - 2.0 * row / self.rows, 1.0 - 2.0 * (row + 1) / self.rows
        phi_lo = -180.0 + 360.0 * col / self.cols
        return {"theta_o_deg": [math.degrees(math.acos(min(1.0, cos_hi))),
                                math.degrees(math.acos(max(-1.0, cos_lo)))],
                "phi_o_deg": [phi_lo, phi_lo + 360.0 / self.cols]}


def _nodes(k: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes u and weights on [0, 1] split into 2 panels of k nodes each."""
    t, w = np.polynomial.legendre.leggauss(k)
    u = (t + 1.0) / 4.0
    return np.concatenate([u, u + 0.5]), np.concatenate([w, w]) / 4.0


def _integrals(grid: Grid, pdf_fn, bins: np.ndarray, k: int) -> tuple[np.ndarray, int]:
    """∫pdf dω over each bin of ``bins`` with k nodes per panel and axis; (values, non-finite
    pdf values set to 0)."""
    u, wu = _nodes(k)
    hx, hy = 2.0 * math.pi / grid.cols, 2.0 / grid.rows
    uu, vv = (a.ravel() for a in np.meshgrid(u, u, indexing="ij"))
    ww = np.outer(wu, wu).ravel() * hx * hy
    out, bad = np.empty(len(bins)), 0
    per = max(1, CHUNK // len(ww))
    for start in range(0, len(bins), per):
        b = bins[start:start + per]
        row, col = np.divmod(b, grid.cols)
        x = (-math.pi + col * hx)[:, None] + hx * uu[None]
        y = (-1.0 + row * hy)[:, None] + hy * vv[None]
        cos = -y.ravel()
        sin = np.sqrt(np.maximum(0.0, 1.0 - cos * cos))
        wo = np.stack([sin * np.cos(x.ravel()), sin * np.sin(x.ravel()), cos], axis=1)
        p = np.asarray(pdf_fn(wo), np.float64)
        finite = np.isfinite(p)
        bad += int((~finite).sum())
        out[start:start + per] = (np.where(finite, p, 0.0).reshape(len(b), -1) * ww).sum(axis=1)
    return out, bad


def tolerance(expected: np.ndarray, bins: int) -> np.ndarray:
    """τ(E) of the module docstring: the integration error a bin of expected count E may have."""
    e = np.abs(expected)
    return np.maximum(EPS * np.maximum(e / np.sqrt(np.maximum(e, POOL)), math.sqrt(POOL) / bins),
                      FLOAT32_REL * e)


def expected_counts(grid: Grid, pdf_fn, n: int, k0: int, k_max: int) -> tuple[np.ndarray, dict]:
    """N·∫pdf per bin (rows, cols), refined per bin until I_k and I_{k/2} agree to
    :func:`tolerance`; and what it took (``integration`` record of the cell).

    ``pdf_fn`` maps directions (M, 3) to pdf values (M,).
    """
    bins = np.arange(grid.rows * grid.cols)
    prev, bad = _integrals(grid, pdf_fn, bins, k0)
    value, error = prev * n, np.zeros(len(bins))
    active, k, evals = bins, k0, len(bins) * (2 * k0) ** 2
    while len(active) and 2 * k <= k_max:
        k *= 2
        cur, b = _integrals(grid, pdf_fn, active, k)
        bad, evals = bad + b, evals + len(active) * (2 * k) ** 2
        err = np.abs(cur - prev[active]) * n
        value[active], error[active], prev[active] = cur * n, err, cur
        done = err <= tolerance(cur * n, len(bins))
        active = active[~done]
    unconverged = np.zeros(len(bins), bool)
    unconverged[active] = True
    info = {"nodes_per_axis_max": 2 * k, "pdf_evaluations": int(evals),
            "unconverged": int(len(active)),
            "max_error_unconverged": float(error[active].max()) if len(active) else 0.0,
            "nonfinite_pdf_dropped": bad, "eps": EPS, "float32_rel": FLOAT32_REL}
    return value.reshape(grid.shape), info


#: |obs − exp| / √max(exp, 1) beyond which :func:`recheck` integrates a bin at the cap.
RECHECK_Z = 4.0
#: Bins per cell that :func:`recheck` integrates again, the most discrepant first.
RECHECK_BINS = 16
#: Expected count of a bin that meets the pdf's support in a sliver the nodes miss.
SLIVER = 1e-9


#: Graded panels toward a peak: edges at distance h·2^-j (j = 0 .. PEAK_LEVELS) on each side,
#: h the bin's side, so a core 2^-PEAK_LEVELS of a bin wide is resolved -- but no finer than
#: a direction can be told apart in float32, where the pdf is evaluated (:data:`PEAK_FINEST`).
PEAK_LEVELS = 30
PEAK_NODES = 8
#: The narrowest panel toward a peak, in radians on the sphere: a quarter of float32's
#: 2^-24 spacing of a unit direction's components (the pdf is a staircase on that grid, so
#: narrower panels only integrate the same steps again).  In the bins' coordinates an angle
#: δ at polar angle θ is δ / sin θ in φ and sin θ·δ + δ²/2 in −cos θ (:func:`_finest`).
PEAK_FINEST = 2.0 ** -26


def angle(d: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Angle between each unit direction of ``d`` (N, 3) and the unit ``c``, accurate for tiny
    angles (2 asin(|d − c|/2); arccos(d·c) loses them below ~1e-4 rad to rounding)."""
    return 2.0 * np.arcsin(np.clip(np.linalg.norm(d - c, axis=1) / 2.0, 0.0, 1.0))


def _finest(y0: float) -> tuple[float, float]:
    """(Δφ, Δ(−cos θ)) of :data:`PEAK_FINEST` radians at −cos θ = y0."""
    sin = math.sqrt(max(0.0, 1.0 - y0 * y0))
    return (PEAK_FINEST / max(sin, PEAK_FINEST),
            sin * PEAK_FINEST + 0.5 * PEAK_FINEST * PEAK_FINEST)


def _graded(lo: float, hi: float, x0: float, finest: float = 0.0) -> np.ndarray:
    """Panel edges of [lo, hi]: its ends and x0 ± (hi − lo)·2^-j, j = 0..PEAK_LEVELS, inside,
    the last level the first whose distance is ≤ ``finest``."""
    levels = PEAK_LEVELS
    if finest > 0.0:
        levels = min(levels, max(0, math.ceil(math.log2((hi - lo) / finest))))
    d = (hi - lo) * 2.0 ** -np.arange(levels + 1, dtype=np.float64)
    e = np.concatenate([[lo, hi, x0], x0 - d, x0 + d])
    return np.unique(e[(e >= lo) & (e <= hi)])


def _panel_rule(edges: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    t, w = np.polynomial.legendre.leggauss(k)
    a, b = edges[:-1, None], edges[1:, None]
    return ((a + b) / 2 + (b - a) / 2 * t).ravel(), ((b - a) / 2 * w).ravel()


def _peak_rule(grid: Grid, b: int, x0: float, y0: float, k: int) -> tuple:
    """(directions (M, 3), weights (M,)) of :func:`peak_integrals`' rule over bin ``b``."""
    row, col = divmod(int(b), grid.cols)
    hx, hy = 2.0 * math.pi / grid.cols, 2.0 / grid.rows
    xlo, ylo = -math.pi + col * hx, -1.0 + row * hy
    # the peak's φ nearest the bin (the seam at φ = ±π)
    x0 = min((x0 + m * 2.0 * math.pi for m in (-1, 0, 1)),
             key=lambda v: abs(min(max(v, xlo), xlo + hx) - v))
    fx, fy = _finest(y0)
    x, wx = _panel_rule(_graded(xlo, xlo + hx, min(max(x0, xlo), xlo + hx), fx), k)
    y, wy = _panel_rule(_graded(ylo, ylo + hy, min(max(y0, ylo), ylo + hy), fy), k)
    cos = -y
    sin = np.sqrt(np.maximum(0.0, 1.0 - cos * cos))
    wo = np.stack([np.multiply.outer(np.cos(x), sin), np.multiply.outer(np.sin(x), sin),
                   np.broadcast_to(cos, (len(x), len(y)))], axis=-1).reshape(-1, 3)
    return wo, np.outer(wx, wy).ravel()


def peak_integrals(grid: Grid, pdf_fn, bins, x0: float, y0: float,
                   orders: tuple[int, ...]) -> list[np.ndarray]:
    """∫pdf over each bin of ``bins``, per Gauss-Legendre order k of ``orders``, by a tensor
    rule in (φ, −cos θ) whose panels are graded toward the point (x0, y0) on each axis and cut
    at the bin's edges (so the bin's indicator is integrated exactly): a peak far narrower
    than the bin is resolved.  The rules go to ``pdf_fn`` together, up to :data:`CHUNK`
    directions a query."""
    rules = [_peak_rule(grid, b, x0, y0, k) for k in orders for b in bins]
    sums, batch = [], []
    for i, rule in enumerate(rules):
        batch.append(rule)
        if i + 1 < len(rules) and sum(len(w) for _, w in batch) + len(rules[i + 1][1]) <= CHUNK:
            continue
        p = np.asarray(pdf_fn(np.concatenate([wo for wo, _ in batch])), np.float64)
        p = np.where(np.isfinite(p), p, 0.0)
        start = 0
        for _, w in batch:
            sums.append(float((p[start:start + len(w)] * w).sum()))
            start += len(w)
        batch = []
    return [np.array(sums[j * len(bins):(j + 1) * len(bins)]) for j in range(len(orders))]


def _peaks(grid: Grid, pdf_fn, n: int, e: np.ndarray, o: np.ndarray, wo: np.ndarray,
           index: np.ndarray, bins: np.ndarray, info: dict) -> np.ndarray:
    """``e`` with a lobe narrower than the finest node spacing integrated: for each rechecked
    bin whose count still contradicts it (> RECHECK_Z σ: a node missed the peak, or hit it and
    weighted it by a whole node's area) and where the pdf is > 0 at one of its samples, that bin and its 8 neighbours are integrated again by
    :func:`peak_integrals`, graded toward the bin's sample of largest pdf.  The samples only
    place the grading; the value is the pdf's alone (a finer rule of the same integral), so a
    sampler that disagrees with its pdf still fails.  A rough dielectric between nearly equal IORs has such a lobe:
    its transmission lobe's core is α·|1 − η|/η wide (2.8·10⁻⁶ rad at α = 0.01,
    η = 1/1.000277), which no tensor rule over 50 × 101 bins finds.  ``info`` gains ``peaks``
    (centre, the bins integrated, their integral and its |I_k − I_{k/2}|)."""
    peaks, done = [], set()
    for b in bins:
        z = abs(o[b] - e[b]) / math.sqrt(max(e[b], 1.0))
        if z <= RECHECK_Z or o[b] < 2 or int(b) in done:
            continue
        # grade toward the lobe's peak: the bin's sample of largest pdf (a skewed lobe's mean
        # may lie many core widths from its peak)
        inside = wo[index == b]
        p = np.asarray(pdf_fn(inside), np.float64)
        if not (np.isfinite(p) & (p > 0)).any():
            continue
        c = inside[int(np.nanargmax(np.where(np.isfinite(p), p, -1.0)))]
        x0, y0 = math.atan2(c[1], c[0]), -c[2]
        row, col = divmod(int(b), grid.cols)
        around = sorted({((row + i) % grid.rows) * grid.cols + (col + j) % grid.cols
                         for i in (-1, 0, 1) for j in (-1, 0, 1)
                         if 0 <= row + i < grid.rows} - done)
        fine, coarse = peak_integrals(grid, pdf_fn, around, x0, y0,
                                      (PEAK_NODES, PEAK_NODES // 2))
        e[around] = fine * n
        done.update(around)
        peaks.append({"bin": int(b), "centre": c.tolist(), "bins": around,
                      "integral": float(fine.sum()),
                      "error": float(np.abs(fine - coarse).sum())})
    info["peaks"] = peaks
    return e


def recheck(grid: Grid, pdf_fn, n: int, expected: np.ndarray, wo: np.ndarray, k_max: int,
            info: dict, index: np.ndarray | None = None) -> np.ndarray:
    """``expected`` with the bins whose count of the directions ``wo`` contradicts it
    integrated again at k_max/2 and k_max nodes per panel: the :data:`RECHECK_BINS` worst with
    |O − E| > RECHECK_Z·√max(E, 1), and every bin holding samples where E = 0.

    The two-level test of :func:`expected_counts` is blind to a lobe narrower than the node
    spacing of both levels (both miss it and agree); the samples then land where E ≈ 0.  A
    bin integrated again is only made more accurate, so this cannot hide a sampling defect,
    and for a correct BSDF under H0 a bin exceeds 4σ with probability 6·10⁻⁵.  A bin still at
    E = 0 whose samples have pdf > 0 at their own directions meets the support in a sliver
    thinner than the nodes (a shadowed region's edge): it gets E = :data:`SLIVER`, so the test
    pools it instead of calling its samples impossible; samples where pdf = 0 stay impossible.
    A bin that still contradicts its count after that is integrated with its neighbours by
    panels graded toward its sample of largest pdf (:func:`_peaks`: a lobe far narrower than
    any node).  ``info`` (the cell's ``integration`` record) gains ``rechecked``, their error
    estimate, ``peaks`` and ``slivers``.  ``index``: ``grid.index(wo)`` when already computed
    (the histogram's).
    """
    e = expected.ravel().copy()
    index = grid.index(wo) if index is None else index
    o = np.bincount(index, minlength=e.size).astype(np.float64)
    z = np.abs(o - e) / np.sqrt(np.maximum(e, 1.0))
    worst = np.flatnonzero(z > RECHECK_Z)
    worst = worst[np.argsort(-z[worst], kind="stable")][:RECHECK_BINS]
    bins = np.union1d(worst, np.flatnonzero((e == 0) & (o > 0)))
    info.update(rechecked=int(len(bins)), recheck_error_max=0.0, slivers=0)
    if len(bins) and k_max >= 2:
        coarse, bad1 = _integrals(grid, pdf_fn, bins, k_max // 2)
        fine, bad2 = _integrals(grid, pdf_fn, bins, k_max)
        e[bins] = fine * n
        info["recheck_error_max"] = float(np.max(np.abs(fine - coarse)) * n)
        info["pdf_evaluations"] += len(bins) * ((k_max) ** 2 + (2 * k_max) ** 2)
        info["nonfinite_pdf_dropped"] += bad1 + bad2
    if len(bins) and k_max >= 2:
        e = _peaks(grid, pdf_fn, n, e, o, wo, index, bins, info)
    empty = (e == 0) & (o > 0)
    if empty.any():
        inside = empty[index]
        p = np.asarray(pdf_fn(wo[inside]), np.float64)
        slivers = np.unique(index[inside][np.isfinite(p) & (p > 0)])
        e[slivers] = SLIVER
        info["slivers"] = int(len(slivers))
    return e.reshape(expected.shape)
