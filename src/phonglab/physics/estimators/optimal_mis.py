r"""``mis_optimal``: a pilot chooses the allocation and the weights, the main stage estimates.

Optimal MIS weights for the two strategies t ∈ {b, l} (BSDF and light
sampling) [Kondapaneni, Vévoda, Grittmann, Skřivan, Slusallek, Křivánek, "Optimal Multiple
Importance Sampling", ACM TOG 38(4), SIGGRAPH 2019, §4–5] with the allocation c_t = n_t/n
between them chosen from a pilot [Sbert, Havran, Szirmay-Kalos, "Multiple importance
sampling revisited: breaking the bounds", EURASIP J. Adv. Signal Process. 2018].  For a fixed
allocation the optimal weights are w_t = α_t p_t/f + (c_t p_t/Σ c p)(1 − Σ_k α_k p_k/f), and the
estimator they give is the balance heuristic applied to f − α·p plus the control variates
∫ p_t = 1::

    F = Σ_t α_t + (1/n) Σ_t Σ_{j ≤ n_t} (f(x_tj) − α·p(x_tj)) / (c·p(x_tj)),      x_tj ~ p_t
    A α = b,   A_tk = ∫ p_t p_k / (c·p) dx,   b_t = ∫ f p_t / (c·p) dx              (2×2)
    n·Var F = σ²(c) = ∫ (f − α·p)² / (c·p) dx       (at the solution: ∫ (f − α·p) p_t/(c·p) = 0)

F is unbiased for *any* α that does not depend on its own samples. So the estimate spends a
pilot of M = n·:data:`PILOT_FRACTION` samples (at most :data:`PILOT_MAX`) (M/2 per strategy,
i.e. drawn from q = (p_b + p_l)/2) on choosing c and α, and *discards* it: for each candidate
c_b in :data:`ALLOCATIONS` (c_l = 1 − c_b) the pilot estimates A, b and ∫ f²/(c·p) by
importance sampling, Â = (1/M) Σ_m p pᵀ/((c·p) q) etc. (summed inside the pilot's kernel, in
float64), solves the 2×2 system (a 1×1 one at c_b ∈ {0, 1}, where the absent strategy's α is 0)
and keeps the c with the smallest σ̂²(c) = ∫̂ f²/(c·p) − α̂·b̂ (the pure strategy when within
:data:`PURE_PREFERENCE` of it: heavy tails make the pilot optimistic about mixtures). The other
n − M samples, drawn from fresh streams, give F (the kernel sums their residuals per estimate,
in float64). Its standard error is stratified: Var F = Σ_t n_t s_t²/n², s_t² the sample
variance within strategy t. A BSDF sample that the plugin rejects (pdf 0, a lobe direction
below the horizon) is a point of its own with probability 1 − ∫_{H²} p_b; giving it p_b := 1,
p_l = 0, f = 0 makes its value −α_b/c_b, which is what keeps ∫ p_b = 1 (the control variate)
true, and the "1" cancels in every term above. With f = α·p exactly (a pure lobe inside the
light, a pure light under a wide lobe) σ² = 0 for every c, so no split is penalized.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

from .kernel import Integrand, channel_mean, chunks, row_sums, safe_ratio, uniforms

#: ``mis_optimal``: the pilot's share of the N samples (discarded after it chose α and c).
PILOT_FRACTION = 1.0 / 32.0
#: ``mis_optimal``: the largest pilot (its 2×2 solves cost host time per candidate c).
PILOT_MAX = 2048
#: ``mis_optimal``: the candidate BSDF shares c_b of the main samples (c_l = 1 − c_b).
ALLOCATIONS = tuple(k / 8.0 for k in range(9))
#: ``mis_optimal``: a pure strategy (c_b = 0 or 1) is preferred over a mixture whose pilot
#: variance is not below (1 − this) times the pure strategy's.
PURE_PREFERENCE = 0.1
#: A seed offset that keeps ``mis_optimal``'s pilot streams apart from its main streams.
_PILOT_KEY = 0x6A09E667


def _technique(f: Integrand, is_b, u1, u2):
    """(f, p_b, p_l) at one sample of BSDF sampling where ``is_b``, else of light sampling.

    A symbolic ``if``: a lane runs only its own technique (the LLVM backend skips a branch
    that no lane of a packet takes).  A BSDF sample the plugin rejects (pdf 0, e.g. a lobe
    direction below the horizon) is the *null point* of that technique: f = 0, p_l = 0 and
    p_b := 1 (any positive value; it cancels, module docstring).
    """
    def by_bsdf(u1, u2):
        bs, weight = f.bsdf.sample(f.ctx, f.si, u1, u2)
        valid = bs.pdf > 0
        value = channel_mean(weight) * bs.pdf * f.light.emitted(bs.wo)     # eval · L
        return (dr.select(valid, value, 0.0), dr.select(valid, bs.pdf, 1.0),
                dr.select(valid, f.light.pdf(bs.wo), 0.0))

    def by_light(u1, u2):
        wo, p_l = f.light.sample(u2)
        value, p_b = f.bsdf.eval_pdf(f.ctx, f.si, wo)
        return channel_mean(value) * f.light.radiance, p_b, p_l

    return dr.if_stmt((u1, u2), is_b, by_bsdf, by_light)


def weighted_moments(fv, pb, pl, c_b: float, select):
    """The six per-sample terms w·(p_b², p_b p_l, p_l², f p_b, f p_l, f²), w = 1/((c·p) q), whose
    pilot means are A, b and ∫ f²/(c·p) at the BSDF share c_b (q = (p_b + p_l)/2, the pilot's
    mixture).  Plain arithmetic plus ``select`` (np.where or dr.select): the one formula for
    numpy arrays and for Dr.Jit arrays inside the pilot kernel."""
    d = (c_b * pb + (1.0 - c_b) * pl) * (0.5 * (pb + pl))
    w = select(d > 0, 1.0 / select(d > 0, d, 1.0), 0.0)
    wf = w * fv
    return [w * pb * pb, w * pb * pl, w * pl * pl, wf * pb, wf * pl, wf * fv]


def solve_allocation(mom: np.ndarray, uncovered_b: np.ndarray, uncovered_l: np.ndarray,
                     allocations=ALLOCATIONS) -> tuple[np.ndarray, ...]:
    """(c_b, α_b, α_l, σ²(c_b)) per row from the pilot's moments.

    Args:
        mom: (B, G, 6) pilot means of :func:`weighted_moments` for each candidate c_b.
        uncovered_b / uncovered_l: (B,) whether a pilot sample had f ≠ 0 where p_b (p_l) = 0.
        allocations: the G candidate BSDF shares c_b (c_l = 1 − c_b).

    For each c the 2×2 system A α = b (A = mean w p pᵀ, b = mean w f p) is the pilot's estimate
    of Kondapaneni et al.'s moment matrix and vector, and σ²(c) = mean w f² − αᵀ b the
    per-sample variance of the optimally weighted estimator (module docstring).  At c_b = 0
    or 1 only the present technique's α is fitted (the other is 0), and σ² is infinite when
    that technique alone misses part of f (``uncovered``).  The smallest σ² wins, a pure
    strategy (c_b ∈ {0, 1}) when it is within :data:`PURE_PREFERENCE` of the best.
    """
    abb, abl, all_, bb, bl, sff = np.moveaxis(np.asarray(mom, np.float64), -1, 0)
    det = abb * all_ - abl * abl
    good = det > 1e-9 * abb * all_
    safe = np.where(good, det, 1.0)
    fit_b = bb / np.where(abb > 0, abb, 1.0)
    alpha_b = np.where(good, (bb * all_ - bl * abl) / safe, fit_b)
    alpha_l = np.where(good, (bl * abb - bb * abl) / safe, 0.0)
    ends = np.asarray(allocations, np.float64)
    pure_b, pure_l = ends == 1.0, ends == 0.0
    alpha_b = np.where(pure_b, fit_b, np.where(pure_l, 0.0, alpha_b))
    alpha_l = np.where(pure_l, bl / np.where(all_ > 0, all_, 1.0), np.where(pure_b, 0.0, alpha_l))
    sigma2 = sff - alpha_b * bb - alpha_l * bl
    # Below 10⁻¹² of the second moment it is float64 rounding of an exact fit (σ² = 0).
    sigma2 = np.where(sigma2 <= 1e-12 * sff, 0.0, sigma2)
    # Inside (0, 1) c·p > 0 at every sample (each has p_b > 0 or p_l > 0).
    sigma2 = np.where(pure_b & np.asarray(uncovered_b, bool)[:, None], np.inf, sigma2)
    sigma2 = np.where(pure_l & np.asarray(uncovered_l, bool)[:, None], np.inf, sigma2)
    best = np.argmin(sigma2, axis=1)
    rows = np.arange(len(best))
    for end in (np.flatnonzero(pure_b), np.flatnonzero(pure_l)):
        if end.size:
            e = int(end[0])
            best = np.where(sigma2[:, e] * (1.0 - PURE_PREFERENCE) <= sigma2[rows, best], e, best)
    return ends[best], alpha_b[rows, best], alpha_l[rows, best], sigma2[rows, best]


def choose_allocation(fv: np.ndarray, pb: np.ndarray, pl: np.ndarray,
                      allocations=ALLOCATIONS) -> tuple[np.ndarray, ...]:
    """:func:`solve_allocation` from (B, M) float64 pilot samples f, p_b, p_l (numpy): the first
    M/2 of each row drawn by BSDF sampling, the rest by light sampling (null points carry
    p_b = 1, p_l = 0, f = 0).  The estimator computes the same moments inside its kernel."""
    mom = np.stack([np.stack([t.mean(axis=1) for t in weighted_moments(fv, pb, pl, c, np.where)],
                             axis=-1) for c in allocations], axis=1)
    return solve_allocation(mom, np.any((pb == 0) & (fv != 0), axis=1),
                            np.any((pl == 0) & (fv != 0), axis=1), allocations)


def pilot_size(n: int) -> int:
    """Pilot samples of an n-sample ``mis_optimal`` estimate: n·PILOT_FRACTION, even, in
    [32, PILOT_MAX]."""
    return min(PILOT_MAX, max(32, 2 * int(round(n * PILOT_FRACTION / 2))))


def pilot(f: Integrand, m: int, batches: int, seed: int) -> tuple[np.ndarray, ...]:
    """(c_b, α_b, α_l, σ²) per row from a pilot of m/2 BSDF then m/2 light samples a row.

    The kernel sums :func:`weighted_moments` for every candidate c_b per row (float64), so
    only (batches, G, 6) means and two coverage flags per row come back;
    :func:`solve_allocation` does the 2×2 solves on the host.
    """
    idx, u1, u2, _ = uniforms(m * batches, seed ^ _PILOT_KEY)
    row = mi.UInt32(dr.floor((mi.Float64(idx) + 0.5) * dr.opaque(mi.Float64, 1.0 / m)))
    j = idx - row * dr.opaque(mi.UInt32, m)
    fv, pb, pl = (mi.Float64(x) for x in
                  _technique(f, j < dr.opaque(mi.UInt32, m // 2), u1, u2))
    terms = [t for c in ALLOCATIONS for t in weighted_moments(fv, pb, pl, c, dr.select)]
    zero = mi.Float64(0.0)
    terms += [dr.select((pb == 0) & (fv != 0), 1.0, zero),
              dr.select((pl == 0) & (fv != 0), 1.0, zero)]
    out = row_sums(terms, row, batches) / m
    mom = out[:, :-2].reshape(batches, len(ALLOCATIONS), 6)
    return solve_allocation(mom, out[:, -2] > 0, out[:, -1] > 0)


def optimal_sums(f: Integrand, per: int, n_b: np.ndarray, alpha_b: np.ndarray,
                 alpha_l: np.ndarray, seed: int) -> dict[str, np.ndarray]:
    """Per-row sums of ``mis_optimal``'s main stage: row s draws n_b[s] BSDF samples then
    per − n_b[s] light samples, weighted with its own α (module docstring).

    The kernel sums its residuals R = X − α_b − α_l per row (float64, :func:`~.kernel.row_sums`), so
    only a few numbers per row come back: Σ R and Σ R² over the BSDF samples and over all,
    and the NaN and Inf counts.  α as the kernel holds them (float32) come back too.
    """
    batches = len(n_b)
    idx, u1, u2, _ = uniforms(per * batches, seed)
    # row = ⌊k / per⌋ in float64 (exact here: k < 2³², per ≤ 2²²), not a UInt32 division,
    # which the LLVM backend scalarizes (it cost as much as the BSDF sample itself).
    row = mi.UInt32(dr.floor((mi.Float64(idx) + 0.5) * dr.opaque(mi.Float64, 1.0 / per)))
    width = dr.opaque(mi.UInt32, per)

    def table(kind, values, dtype):
        # Padded to >= 2 entries: a 1-entry gather source compiles a different kernel.
        return dr.gather(kind, kind(np.append(values, values[-1:]).astype(dtype)), row)

    is_b = (idx - row * width) < table(mi.UInt32, n_b, np.uint32)
    fv, pb, pl = _technique(f, is_b, u1, u2)
    a_b = table(mi.Float, alpha_b, np.float32)
    a_l = table(mi.Float, alpha_l, np.float32)
    c_b = table(mi.Float, n_b / per, np.float32)
    r = safe_ratio(fv - a_b * pb - a_l * pl, c_b * pb + (1.0 - c_b) * pl)
    r64 = mi.Float64(r)
    sq = r64 * r64
    zero = mi.Float64(0.0)
    names = ("sum_b", "sum", "sq_b", "sq", "nan", "inf")
    sums = row_sums([dr.select(is_b, r64, zero), r64, dr.select(is_b, sq, zero), sq,
                      dr.select(dr.isnan(r), 1.0, zero), dr.select(dr.isinf(r), 1.0, zero)],
                     row, batches)
    out = {k: sums[:, i] for i, k in enumerate(names)}
    out["alpha"] = (alpha_b.astype(np.float32).astype(np.float64)
                    + alpha_l.astype(np.float32).astype(np.float64))
    return out


def run_optimal(f: Integrand, n: int, batches: int, seed: int, chunk: int) -> tuple:
    """(values, stderr, NaN count, Inf count) of ``batches`` mis_optimal estimates of ``f``,
    launched in chunks of <= ``chunk`` samples."""
    m = pilot_size(n)
    per = n - m
    values, stderr, nan, inf = [], [], 0, 0
    for _, b, chunk_seed in chunks(batches, max(1, chunk // n), seed):
        c_b, alpha_b, alpha_l, _ = pilot(f, m, b, chunk_seed)
        n_b = np.rint(c_b * per).astype(np.int64)
        t = optimal_sums(f, per, n_b, alpha_b, alpha_l, chunk_seed)
        values.append(t["alpha"] + t["sum"] / per)
        # Stratified: Var = Σ_t k_t s_t² / per², s_t² the variance within technique t.
        var = np.zeros(b)
        for k, total, squares in ((n_b, t["sum_b"], t["sq_b"]),
                                  (per - n_b, t["sum"] - t["sum_b"], t["sq"] - t["sq_b"])):
            ss = np.maximum(squares - total * total / np.maximum(k, 1), 0.0)
            var += ss / np.maximum(k - 1, 1) * k
        stderr.append(np.sqrt(var) / per)
        nan += int(t["nan"].sum())
        inf += int(t["inf"].sum())
    return np.concatenate(values), np.concatenate(stderr), nan, inf

