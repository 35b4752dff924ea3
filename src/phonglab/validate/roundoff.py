r"""Float32 round-off: the tolerance of every identity topic of every kind, and the conditioning
of the compared values.

Round-off tolerance of the identities (``eval_pdf``, ``weight``, ``pdf``, ``reciprocity``,
``component``).  Mitsuba computes in float32 (unit round-off u = 2⁻²⁴ ≈ 6e-8).  The two sides
of an identity are the same mathematical value computed by different code paths (a microfacet
weight F·G/G₁ against eval/pdf = F·D·G/(4 cos θ_i) / (G₁ D/(4 cos θ_i)), a lobe sum in another
order, ...).  Each path is a chain of at most a few hundred float32 operations, including
a few subtractions (1 − cos, Fresnel) that can lose up to ~10 bits to cancellation near grazing;
:data:`REL_TOL` = 2¹⁴ u = 2⁻¹⁰ ≈ 9.8e-4 bounds the relative difference
|a − b| / max(|a|, |b|), with a floor for values that are both ≈ 0 (:func:`rel_diff`).  A planted
defect that is off by a factor (×1.1, ×2u₁, ...) is off by ≥ 1e-2 on most lanes.

Conditioning.  Where one side is evaluated at a direction another computation produced
(``weight`` and ``pdf`` at the sampled wo, ``reciprocity`` with the roles swapped), the float32
rounding of that direction (≤ u/2 per component) is amplified by the function's condition
number, which is large at grazing configurations (a half vector ω_i + ω_o that cancels, a
lobe's steep tail).  :func:`sensitivity` measures it per lane: the relative change of the
compared value when both directions move by :data:`PERTURB` = 8u per component (absolute,
about 16× the rounding of a computed unit vector), the largest over :data:`DRAWS` random sign patterns (one pattern can miss the
ill-conditioned combination), and the lane's tolerance is REL_TOL + that sensitivity.  The row reports
max_lanes rel_diff / (REL_TOL + sensitivity), which must be ≤ 1.

Random corners can miss a thin set.  At a grazing retro-reflection (|ω_i + ω_o| ≈ 1e-4) a
microfacet pdf is non-zero only where |ω_o|² − |ω_i|² lies within |ω_i + ω_o|²
≈ 1.5e-8 < u of 0 (the side tests ω_i·m > 0, ω_o·m > 0 with m = normalize(ω_i + ω_o)), and every
8u corner lands outside it: pdf = 0 at all of them, against bs.pdf = 2348.7 from the exact m.
So a lane that fails with the random estimate gets a second, deterministic one,
:func:`box_sensitivity`: the largest relative change of the evaluated side over EVERY
float32 direction whose components lie within :data:`ULPS` = 8 ulps of the sampled wo's
((2·8 + 1)³ = 4913 points; wi is the lanes' exact input, the rounding is wo's).  The lane's
sensitivity is the larger of the two estimates (both are maxima over subsets of the same
rounding error set, so their union is the better estimate); :func:`refine` searches the
failing lanes worst first and stops at the first batch with a lane that still fails (the row
fails; lanes not searched keep the random estimate, so ``measured`` is then an upper bound).
This does not loosen the check where it matters: a lane with relative condition number κ gets
at most ≈ κ·8·2⁻²³ added to 2⁻¹⁰, i.e. < 10 % more for κ < 100, and a planted defect
(a factor off on a smooth lobe) changes by ~1e-6 over the box and still fails.
"""

from __future__ import annotations

import numpy as np

#: float32 unit round-off 2⁻²⁴.
EPS32 = 2.0 ** -24
#: Relative tolerance of a float32 identity: 2¹⁴ unit round-offs (see the module docstring).
REL_TOL = 2.0 ** 14 * EPS32
#: Absolute floor below which two values count as equal (both ≈ 0 in float32 terms).
ABS_FLOOR = 1e-6


#: Relative perturbation of each direction component for :func:`sensitivity`: 8 unit round-offs.
PERTURB = 8 * EPS32


def perturb(v: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Directions v moved by ±PERTURB per component (random signs), NOT renormalized.

    Absolute, not relative, per component: a direction computed in float32 (reflect(wi, m),
    a warp) carries an absolute error of a few u in every component, also in a small one
    (cos θ = 0.004 at grazing), where a relative model would understate it.  Not renormalized:
    a float32 direction is unit only to a few u, and renormalizing would undo the move of a
    component near ±1 -- exactly the one whose rounding a half vector ω_i + ω_o amplifies at
    grazing retro-reflection.
    """
    return np.asarray(v, np.float64) + PERTURB * rng.choice([-1.0, 1.0], size=np.shape(v))


#: Random sign patterns of the perturbation per lane.
DRAWS = 4


def sensitivity(fn, wi: np.ndarray, wo: np.ndarray, rng: np.random.Generator,
                value=None) -> np.ndarray:
    """Per lane: max over DRAWS perturbations of the relative change of fn(wi, wo) (all channels).

    ``fn`` maps (wi (N, 3), wo (N, 3)) to (N,) or (N, C); ``value`` is fn(wi, wo) if known.
    One call of fn for all draws (the lanes are stacked).
    """
    n = len(wi)
    value = fn(wi, wo) if value is None else value
    moved = fn(perturb(np.tile(wi, (DRAWS, 1)), rng), perturb(np.tile(wo, (DRAWS, 1)), rng))
    d = np.nan_to_num(rel_diff(np.tile(value, (DRAWS,) + (1,) * (np.ndim(value) - 1)), moved),
                      nan=0.0)
    d = d.max(axis=1) if d.ndim > 1 else d
    return d.reshape(DRAWS, n).max(axis=0)


#: Radius, in float32 ulps per component, of :func:`box_sensitivity`'s neighbourhood (the 8 of
#: PERTURB for components in [0.5, 1), where one ulp is u).
ULPS = 8
#: Lanes per call of :func:`box_sensitivity` in :func:`refine` (× 4913 points each).
BOX_BATCH = 32


def ulp_box(v: np.ndarray, k: int = ULPS) -> np.ndarray:
    """Every float32 vector within k ulps per component of each row of v: (N·(2k+1)³, 3),
    lane-major (the (2k+1)³ neighbours of v[0] first)."""
    v32 = np.asarray(v, np.float32)
    steps = np.arange(-k, k + 1, dtype=np.float64)
    grid = np.stack(np.meshgrid(steps, steps, steps, indexing="ij"), -1).reshape(-1, 3)
    spacing = np.spacing(np.abs(v32)).astype(np.float64)
    moved = v32.astype(np.float64)[:, None, :] + grid[None] * spacing[:, None, :]
    return moved.astype(np.float32).astype(np.float64).reshape(-1, 3)


def box_sensitivity(fn, wi: np.ndarray, wo: np.ndarray, value, k: int = ULPS) -> np.ndarray:
    """Per lane: max relative change of fn(wi, wo') over every wo' of :func:`ulp_box` (wo, k).

    ``fn`` as in :func:`sensitivity`; ``value`` = fn(wi, wo).  A non-finite neighbour counts as
    no change (non-finite values are the ``finite`` topic's).  Each lane's relative change is
    taken against its own box (:func:`rel_diff`'s floor from that lane's values): with one
    floor for the batch, a lane whose pdf moves from 1.05e5 to 0 within its box (grazing
    retro-reflection) beside lanes of pdf ~1e8 (roughdielectric's near-straight transmission at
    η ≈ 1) got 0.21 instead of 1.0, and which lanes shared a batch decided the row.
    """
    n, m = len(wi), (2 * k + 1) ** 3
    moved = np.asarray(fn(np.repeat(wi, m, axis=0), ulp_box(wo, k)))
    base = np.asarray(value)
    out = np.empty(n)
    for j in range(n):
        block = moved[j * m:(j + 1) * m]
        d = np.nan_to_num(rel_diff(np.repeat(base[j:j + 1], m, axis=0), block), nan=0.0)
        out[j] = float(d.max()) if d.size else 0.0
    return out


def refine(rel: np.ndarray, sens: np.ndarray, other: np.ndarray, fn, wi: np.ndarray,
           wo: np.ndarray, value) -> tuple[np.ndarray, dict]:
    """Per-lane excess with the evaluated side's sensitivity ``sens`` raised to
    :func:`box_sensitivity` for the lanes that fail (``other``: the sampler side's, unchanged).

    Failing lanes are searched worst first, :data:`BOX_BATCH` at a time, until one still fails
    after its box (the row fails then; the lanes not searched keep the random estimate).
    Returns (excess, {"box_searched", "box_passed", "box_stopped_early"}).
    """
    ex = excess(rel, sens + other)
    order = np.flatnonzero(ex > 1.0)
    order = order[np.argsort(-ex[order], kind="stable")]
    searched = passed = 0
    for start in range(0, len(order), BOX_BATCH):
        lanes = order[start:start + BOX_BATCH]
        box = box_sensitivity(fn, wi[lanes], wo[lanes], np.asarray(value)[lanes])
        ex[lanes] = np.minimum(ex[lanes], excess(rel[lanes], np.maximum(sens[lanes], box)
                                                 + other[lanes]))
        searched += len(lanes)
        passed += int(np.sum(ex[lanes] <= 1.0))
        if np.any(ex[lanes] > 1.0):
            break
    return ex, {"box_searched": searched, "box_passed": passed,
                "box_stopped_early": bool(searched < len(order))}


def excess(rel: np.ndarray, sens: np.ndarray) -> np.ndarray:
    """rel_diff measured against the lane's tolerance REL_TOL + sensitivity (≤ 1 passes)."""
    return rel / (REL_TOL + sens)


def invalid(*arrays) -> np.ndarray:
    """Per lane: NaN, ±inf or a negative value in any channel of any of ``arrays`` (a value, a
    pdf, a weight: none of them may be)."""
    out = None
    for a in arrays:
        a = np.asarray(a, np.float64)
        b = ~np.isfinite(a) | (a < 0)
        b = b.any(axis=1) if b.ndim > 1 else b
        out = b if out is None else out | b
    return out


def rel_diff(a, b) -> np.ndarray:
    """|a − b| / max(|a|, |b|, floor), elementwise; NaN where either side is not finite.

    floor = max(ABS_FLOOR, REL_TOL · median |b| over b's non-zero finite values): a difference
    far below the quantity's own scale (a weight of 5e-8 against 0 where weights are ~0.5) is
    round-off level, not a relative error of 100 %.
    """
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    mags = np.abs(b[np.isfinite(b) & (b != 0)])
    floor = max(ABS_FLOOR, REL_TOL * float(np.median(mags))) if mags.size else ABS_FLOOR
    d = np.abs(a - b) / np.maximum(np.maximum(np.abs(a), np.abs(b)), floor)
    return np.where(np.isfinite(a) & np.isfinite(b), d, np.nan)
