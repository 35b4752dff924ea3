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

Cost: the pilot, the 2×2 solves and the main stage are three kernels that run back to
back on the device, nothing read back between them (the solves are one lane per estimate, by
Cramer's rule; the main stage gathers its row's n_b and α); a pilot lane draws one sample of
each strategy and a main-stage lane two samples, which halves what a lane costs besides its
samples (seeding its stream, the gathers, the atomic sums).  The three are one frozen function
(``dr.freeze``, :data:`FROZEN`): traced and recorded once per size, replayed afterwards, so an
estimate does not pay the tracing of its ~600 Dr.Jit operations and the code generation of
three kernels at every call, which cost as much as running them at 16 × 2¹⁴ samples.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

from .kernel import (Integrand, KernelLight, channel_mean, chunks, row_column, row_sums,
                     row_sums_device, safe_ratio, uniforms)

#: ``mis_optimal``: the pilot's share of the N samples (discarded after it chose α and c).
PILOT_FRACTION = 1.0 / 32.0
#: ``mis_optimal``: the largest pilot (its samples are discarded: an upper bound on that loss).
PILOT_MAX = 2048
#: ``mis_optimal``: the candidate BSDF shares c_b of the main samples (c_l = 1 − c_b).
ALLOCATIONS = tuple(k / 8.0 for k in range(9))
#: ``mis_optimal``: a pure strategy (c_b = 0 or 1) is preferred over a mixture whose pilot
#: variance is not below (1 − this) times the pure strategy's.
PURE_PREFERENCE = 0.1
#: A seed offset that keeps ``mis_optimal``'s pilot streams apart from its main streams.
_PILOT_KEY = 0x6A09E667


def _by_bsdf(f: Integrand, u1, u2):
    """(f, p_b, p_l) at a sample of BSDF sampling.  A BSDF sample the plugin rejects (pdf 0,
    e.g. a lobe direction below the horizon) is the *null point* of that technique: f = 0,
    p_l = 0 and p_b := 1 (any positive value; it cancels, module docstring)."""
    bs, weight = f.bsdf.sample(f.ctx, f.si, u1, u2)
    valid = bs.pdf > 0
    value = channel_mean(weight) * bs.pdf * f.light.emitted(bs.wo)     # eval · L
    return (dr.select(valid, value, 0.0), dr.select(valid, bs.pdf, 1.0),
            dr.select(valid, f.light.pdf(bs.wo), 0.0))


def _by_light(f: Integrand, u1, u2):
    """(f, p_b, p_l) at a sample of light sampling (``u1`` unused)."""
    wo, p_l = f.light.sample(u2)
    value, p_b = f.bsdf.eval_pdf(f.ctx, f.si, wo)
    return channel_mean(value) * f.light.radiance, p_b, p_l


def _technique(f: Integrand, is_b, u1, u2):
    """(f, p_b, p_l) at one sample of BSDF sampling where ``is_b``, else of light sampling.

    A symbolic ``if``: a lane runs only its own technique (the LLVM backend skips a branch
    that no lane of a packet takes).
    """
    return dr.if_stmt((u1, u2), is_b, lambda u1, u2: _by_bsdf(f, u1, u2),
                      lambda u1, u2: _by_light(f, u1, u2))


def _rows(lanes_per_row: int, rows: int, seed: int):
    """(row, lane within its row, rng) of ``rows`` rows of ``lanes_per_row`` lanes each; lane
    k draws from PCG32 stream TEA(seed, k)."""
    idx, _, _, rng = uniforms(lanes_per_row * rows, seed)
    # row = ⌊k / lanes⌋ in float64 (exact here: k < 2³², lanes ≤ 2²²), not a UInt32 division,
    # which the LLVM backend scalarizes (it cost as much as the BSDF sample itself).
    row = mi.UInt32(dr.floor((mi.Float64(idx) + 0.5) * dr.opaque(mi.Float64, 1.0 / lanes_per_row)))
    return row, idx - row * dr.opaque(mi.UInt32, lanes_per_row), rng


def _draw(rng):
    """(u1, u2) of one sample from a lane's stream."""
    u1 = rng.next_float32()
    return u1, mi.Point2f(rng.next_float32(), rng.next_float32())


def weighted_moments(fv, pb, pl, c_b: float, select):
    """The six per-sample terms w·(p_b², p_b p_l, p_l², f p_b, f p_l, f²), w = 1/((c·p) q), whose
    pilot means are A, b and ∫ f²/(c·p) at the BSDF share c_b (q = (p_b + p_l)/2, the pilot's
    mixture).  Plain arithmetic plus ``select`` (np.where or dr.select): the one formula for
    numpy arrays and for Dr.Jit arrays inside the pilot kernel."""
    d = (c_b * pb + (1.0 - c_b) * pl) * (0.5 * (pb + pl))
    w = select(d > 0, 1.0 / select(d > 0, d, 1.0), 0.0)
    wf = w * fv
    return [w * pb * pb, w * pb * pl, w * pl * pl, wf * pb, wf * pl, wf * fv]


def solve_moments(columns, uncovered_b, uncovered_l, allocations, select):
    """(c_b, α_b, α_l, σ²(c_b)) per row from the pilot's moments, for numpy or Dr.Jit arrays.

    Args:
        columns: one tuple (A_bb, A_bl, A_ll, b_b, b_l, ∫f²/(c·p)) of row arrays per candidate.
        uncovered_b / uncovered_l: per row, whether a pilot sample had f ≠ 0 where p_b (p_l) = 0.
        allocations: the candidate BSDF shares c_b (c_l = 1 − c_b), one per column.
        select: ``np.where`` or ``dr.select``: plain arithmetic and ``select`` only, so that
            the same formula solves on the host (:func:`solve_allocation`) and inside the
            device's kernel (:func:`pilot`).

    For each c the 2×2 system A α = b (A = mean w p pᵀ, b = mean w f p) is the pilot's estimate
    of Kondapaneni et al.'s moment matrix and vector, solved by Cramer's rule, and σ²(c) =
    mean w f² − αᵀ b the per-sample variance of the optimally weighted estimator (module
    docstring).  At c_b = 0 or 1 only the present technique's α is fitted (the other is 0),
    and σ² is infinite when that technique alone misses part of f (``uncovered``).  The
    smallest σ² wins (the first on a tie), a pure strategy (c_b ∈ {0, 1}) when it is within
    :data:`PURE_PREFERENCE` of the best.
    """
    best, ends = None, []
    for c, (abb, abl, all_, bb, bl, sff) in zip(allocations, columns):
        fit_b = bb / select(abb > 0, abb, 1.0)
        if c == 1.0:
            alpha_b, alpha_l = fit_b, 0.0 * bb
        elif c == 0.0:
            alpha_b, alpha_l = 0.0 * bb, bl / select(all_ > 0, all_, 1.0)
        else:
            det = abb * all_ - abl * abl
            good = det > 1e-9 * abb * all_
            safe = select(good, det, 1.0)
            alpha_b = select(good, (bb * all_ - bl * abl) / safe, fit_b)
            alpha_l = select(good, (bl * abb - bb * abl) / safe, 0.0)
        sigma2 = sff - alpha_b * bb - alpha_l * bl
        # Below 10⁻¹² of the second moment it is float64 rounding of an exact fit (σ² = 0).
        sigma2 = select(sigma2 <= 1e-12 * sff, 0.0, sigma2)
        # Inside (0, 1) c·p > 0 at every sample (each has p_b > 0 or p_l > 0).
        if c in (0.0, 1.0):
            sigma2 = select(uncovered_b if c == 1.0 else uncovered_l, np.inf, sigma2)
        share = select(sigma2 == sigma2, c, c)             # c as an array of the rows' shape
        candidate = (share, alpha_b, alpha_l, sigma2)
        if c in (0.0, 1.0):
            ends.append((c, candidate))
        if best is None:
            best = candidate
        else:
            take = sigma2 < best[3]
            best = tuple(select(take, x, y) for x, y in zip(candidate, best))
    for _, end in sorted(ends, key=lambda e: -e[0]):            # c_b = 1 first, then 0
        take = end[3] * (1.0 - PURE_PREFERENCE) <= best[3]
        best = tuple(select(take, x, y) for x, y in zip(end, best))
    return best


def solve_allocation(mom: np.ndarray, uncovered_b: np.ndarray, uncovered_l: np.ndarray,
                     allocations=ALLOCATIONS) -> tuple[np.ndarray, ...]:
    """(c_b, α_b, α_l, σ²(c_b)) per row from (B, G, 6) pilot means of :func:`weighted_moments`
    for each of the G candidate shares c_b, on the host (:func:`solve_moments`)."""
    mom = np.asarray(mom, np.float64)
    columns = [tuple(mom[:, g, k] for k in range(6)) for g in range(mom.shape[1])]
    return tuple(np.asarray(x, np.float64) for x in
                 solve_moments(columns, np.asarray(uncovered_b, bool),
                               np.asarray(uncovered_l, bool), allocations, np.where))


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


def pilot(f: Integrand, m: int, batches: int, seed: int) -> tuple:
    """(c_b, α_b, α_l, σ²) per row from a pilot of m/2 BSDF then m/2 light samples a row, as
    Dr.Jit Float64 arrays of batches + 1 entries (the last a padding row), not yet computed.

    The pilot's kernel sums :func:`weighted_moments` for every candidate c_b per row (float64,
    :func:`~.kernel.row_sums_device`); :func:`solve_moments` traces the 2×2 solves over those
    sums, so they run on the device in a kernel of one lane per row, and nothing comes back to
    the host before the main stage has run (:func:`run_optimal`).
    """
    # A lane draws one BSDF and one light sample: the m/2 + m/2 of its row, no branch.
    row, _, rng = _rows(m // 2, batches, seed ^ _PILOT_KEY)
    samples = [tuple(mi.Float64(x) for x in technique(f, *_draw(rng)))
               for technique in (_by_bsdf, _by_light)]
    terms = [sum(t) for c in ALLOCATIONS
             for t in zip(*(weighted_moments(fv, pb, pl, c, dr.select) for fv, pb, pl in samples))]
    zero = mi.Float64(0.0)
    terms += [sum(dr.select((p == 0) & (fv != 0), 1.0, zero) for fv, p in
                  ((fv, pb) for fv, pb, _ in samples)),
              sum(dr.select((p == 0) & (fv != 0), 1.0, zero) for fv, p in
                  ((fv, pl) for fv, _, pl in samples))]
    sums = row_sums_device(terms, row, batches)
    width, scale = len(terms), dr.opaque(mi.Float64, 1.0 / m)
    mean = [row_column(sums, width, k, batches) * scale for k in range(width)]
    columns = [tuple(mean[6 * g: 6 * g + 6]) for g in range(len(ALLOCATIONS))]
    return solve_moments(columns, mean[-2] > 0, mean[-1] > 0, ALLOCATIONS, dr.select)


def _residuals(f: Integrand, per: int, rows: int, n_b, alpha_b, alpha_l, seed: int):
    """([R₁, R₂], [is_b₁, is_b₂], row) of the main stage, two samples a lane: row s draws
    n_b[s] BSDF samples then per − n_b[s] light samples, R = (f − α·p)/(c·p) with the row's
    own α and c = n_b/per (Dr.Jit arrays of >= 2 entries: a gather source of one entry would
    compile a different kernel); the second sample of a row's last lane is R = 0 when per is
    odd.  Two samples a lane halve what a lane costs besides its samples: its stream's seeding,
    the row's gathers and the sums' atomic adds."""
    lanes = (per + 1) // 2
    row, lane, rng = _rows(lanes, rows, seed)
    n_row = dr.gather(mi.UInt32, n_b, row)
    a_b = dr.gather(mi.Float, alpha_b, row)
    a_l = dr.gather(mi.Float, alpha_l, row)
    c_b = mi.Float(n_row) * dr.opaque(mi.Float, 1.0 / per)
    values, kinds = [], []
    for second in (0, 1):
        j = 2 * lane + second
        is_b = j < n_row
        fv, pb, pl = _technique(f, is_b, *_draw(rng))
        r = safe_ratio(fv - a_b * pb - a_l * pl, c_b * pb + (1.0 - c_b) * pl)
        if second:
            r = dr.select(j < dr.opaque(mi.UInt32, per), r, 0.0)
        values.append(r)
        kinds.append(is_b)
    return values, kinds, row


def _main_sums(f: Integrand, per: int, rows: int, n_b, alpha_b, alpha_l, seed):
    """The main stage's row sums Σ R, Σ R² over the BSDF samples and over all (a
    :func:`~.kernel.row_sums_device` buffer of four values a row, float64)."""
    rs, kinds, row = _residuals(f, per, rows, n_b, alpha_b, alpha_l, seed)
    zero = mi.Float64(0.0)
    r64 = [mi.Float64(r) for r in rs]
    sq = [r * r for r in r64]
    return row_sums_device([sum(dr.select(b, r, zero) for b, r in zip(kinds, r64)),
                            r64[0] + r64[1], sum(dr.select(b, q, zero) for b, q in zip(kinds, sq)),
                            sq[0] + sq[1]], row, rows)


def _stages(bsdf: mi.BSDF, si: mi.SurfaceInteraction3f, light: KernelLight, seed: mi.UInt32,
            m: int, per: int, rows: int):
    """The three kernels of ``rows`` estimates, with nothing read back between them: the pilot,
    the solves (n_b = round(c_b·per), α as float32), the main stage's sums.

    Its arguments are all that varies between calls: Dr.Jit arrays (the BSDF's parameters,
    ω_i, the light's, the seed) and the sizes (Python ints).  :data:`FROZEN` records it
    once per size and replays it (the BSDF context, not a Dr.Jit type, is made here so that
    a new one never forces a new recording).
    """
    f = Integrand(bsdf, si, light, mi.BSDFContext())
    c_b, alpha_b, alpha_l, _ = pilot(f, m, rows, seed)
    n_b = mi.UInt32(dr.round(c_b * dr.opaque(mi.Float64, per)))
    alpha_b, alpha_l = mi.Float(alpha_b), mi.Float(alpha_l)
    dr.eval(n_b, alpha_b, alpha_l)              # the solves: one kernel, one lane per row
    return _main_sums(f, per, rows, n_b, alpha_b, alpha_l, seed), n_b, alpha_b, alpha_l


#: :func:`_stages` as a frozen function (``dr.freeze``): its first calls of a size trace the
#: three kernels and record them, later calls replay the recording with the new arguments, so
#: a call costs the kernels' run time and not the tracing of some 600 Dr.Jit operations and
#: the three kernels' code generation (~1 ms a call, as much as the kernels themselves at
#: 16 × 2¹⁴ samples; docs/speed.md).  The sizes are Python ints: each (m, per, rows) has a
#: recording of its own (``warn_after`` is raised for sweeps over N).
FROZEN = dr.freeze(_stages, warn_after=1000)


def optimal_sums(f: Integrand, per: int, rows: int, n_b, alpha_b, alpha_l, seed,
                 sums=None) -> dict[str, np.ndarray]:
    """Per-row sums of ``mis_optimal``'s main stage (:func:`_residuals`), read back.

    The kernel sums the residuals R = X − α_b − α_l per row (float64,
    :func:`~.kernel.row_sums_device`), so only four numbers per row come back: Σ R and Σ R²
    over the BSDF samples and over all (``sums``, when a frozen :func:`_stages` computed them
    already).  A sum that is not finite (a float32 R is finite, and so are its float64 sums
    and squares, unless some R is NaN or ±Inf) sends the rows through a second kernel that
    counts the NaN and Inf values; otherwise both counts are exactly 0 and the main stage
    costs no counting.
    """
    if sums is None:
        sums = _main_sums(f, per, rows, n_b, alpha_b, alpha_l, seed)
    dr.eval(sums, n_b, alpha_b, alpha_l)
    table = np.array(sums, dtype=np.float64)[:rows * 4].reshape(rows, 4)
    out = {k: table[:, i] for i, k in enumerate(("sum_b", "sum", "sq_b", "sq"))}
    out["n_b"] = np.array(n_b, dtype=np.int64)[:rows]
    out["alpha"] = (np.array(alpha_b, dtype=np.float64)[:rows]
                    + np.array(alpha_l, dtype=np.float64)[:rows])
    out["nan"] = out["inf"] = np.zeros(rows)
    if not np.isfinite(table).all():
        rs, _, row = _residuals(f, per, rows, n_b, alpha_b, alpha_l, seed)
        zero = mi.Float64(0.0)
        counts = row_sums([sum(dr.select(dr.isnan(r), 1.0, zero) for r in rs),
                           sum(dr.select(dr.isinf(r), 1.0, zero) for r in rs)], row, rows)
        out["nan"], out["inf"] = counts[:, 0], counts[:, 1]
    return out


def run_optimal(f: Integrand, n: int, batches: int, seed: int, chunk: int,
                frozen: bool = True) -> tuple:
    """(values, stderr, NaN count, Inf count) of ``batches`` mis_optimal estimates of ``f``,
    launched in chunks of <= ``chunk`` samples.

    Per chunk the pilot's kernel, the solves' kernel (one lane per row) and the main stage's
    kernel run back to back on the device (:func:`_stages`, replayed by :data:`FROZEN`
    unless ``frozen`` is False): n_b = round(c_b (n − m)) and α stay there (the main stage
    gathers them by row) and come back to the host only with the main stage's sums.
    """
    m = pilot_size(n)
    per = n - m
    values, stderr, nan, inf = [], [], 0, 0
    for _, b, chunk_seed in chunks(batches, max(1, chunk // n), seed):
        key = dr.opaque(mi.UInt32, chunk_seed)
        stages = FROZEN if frozen else _stages
        sums, n_b, alpha_b, alpha_l = stages(f.bsdf, f.si, f.light, key, m, per, b)
        t = optimal_sums(f, per, b, n_b, alpha_b, alpha_l, key, sums=sums)
        values.append(t["alpha"] + t["sum"] / per)
        # Stratified: Var = Σ_t k_t s_t² / per², s_t² the variance within technique t.
        var = np.zeros(b)
        for k, total, squares in ((t["n_b"], t["sum_b"], t["sq_b"]),
                                  (per - t["n_b"], t["sum"] - t["sum_b"], t["sq"] - t["sq_b"])):
            ss = np.maximum(squares - total * total / np.maximum(k, 1), 0.0)
            var += ss / np.maximum(k - 1, 1) * k
        stderr.append(np.sqrt(var) / per)
        nan += int(t["nan"].sum())
        inf += int(t["inf"].sum())
    return np.concatenate(values), np.concatenate(stderr), nan, inf
