r"""The algebra of Mueller matrices the polarized topics use (:mod:`.polarization`, where the
criteria are derived): the Stokes-cone margin of a matrix (:func:`stokes_margin`, the smallest
s0' − |s'| over the unit Poincaré sphere), Cloude's coherency matrix and its smallest eigenvalue
(:func:`cloude_min_eig`), the Jones-to-Mueller map, and Mitsuba's implicit Stokes frames
(:func:`stokes_basis`, :func:`rotate_stokes_basis`) with the reversed path's matrix of a
reflection (:func:`reversed_matrix`); the difference of two matrices' polarization parts
M/M00 (:func:`polarization_diff`) and its sensitivity to round-off in the directions
(:func:`sensitivity`).  numpy only.
"""

from __future__ import annotations

import numpy as np

from ..roundoff import perturb


# ----------------------------------------------------------------------------- criteria
def fibonacci(k: int) -> np.ndarray:
    """k nearly uniform unit vectors (a Fibonacci sphere)."""
    i = np.arange(k) + 0.5
    z = 1.0 - 2.0 * i / k
    phi = np.pi * (1.0 + 5 ** 0.5) * i
    s = np.sqrt(1.0 - z * z)
    return np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=1)


def _g(m: np.ndarray, s: np.ndarray) -> np.ndarray:
    """s0' − |s'| of M (N, 4, 4) applied to the Stokes vectors s (N or 1, K, 4): (N, K)."""
    out = np.matmul(m, np.swapaxes(s, -1, -2))                # (N, 4, K)
    return out[:, 0] - np.sqrt(np.sum(out[:, 1:] ** 2, axis=1))


def stokes_margin(m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r"""Per matrix (…, 4, 4): (min over unit u of s0' − |s'| for s = (1, u), the minimizing u).

    A matrix keeps the Stokes cone iff the margin is ≥ 0 (the module docstring).  A grid of
    :data:`GRID` directions (spacing ≈ 0.1 rad), then 40 steps of a shrinking random local
    search (6 candidates a step, the step from 0.15 down to 2e-6 rad) from each of the
    :data:`STARTS` best grid points.  This is a numerical minimization, not a certified
    global one: g is smooth (a linear function minus the norm of an affine one), so a violation
    whose region on the sphere holds no grid point and lies outside the basins of the best
    ones could be missed; the tests check it against matrices whose margin is known (Jones
    matrices: 0 everywhere; over-polarizers, M00 < 0, amplified circular polarization).
    The zero matrix (margin 0) is not searched, equal matrices once.

    A matrix whose grid minimum already proves the margin positive is not searched either: its
    margin is returned as the grid minimum (an upper bound of the true one, both > 0; a
    positive margin is all the criterion asks, so the rows are the same).  The proof: write
    M = [[m00, aᵀ], [c, N]], so g(u) = m00 + a·u − |c + N u|.  For unit u, v,

        |g(u) − g(v)| ≤ |a·(u − v)| + | |c + N u| − |c + N v| | ≤ (|a| + ‖N‖₂) |u − v|

    (Cauchy–Schwarz, the reverse triangle inequality), so g is L-Lipschitz in the chordal
    distance with L = |a| + ‖N‖₂.  Every unit u lies within chordal distance :data:`COVER` of
    a grid point (the grid's covering radius), hence min_u g ≥ min_grid g − L·COVER, and
    min_grid g − L·COVER > 0 certifies a positive margin.  The covering radius of a point set
    on the sphere is the largest circumradius of its spherical Delaunay triangles (the point
    of the sphere farthest from the set is a Voronoi vertex, the circumcentre of a Delaunay
    triangle), i.e. of the facets of its convex hull: for the 512-point Fibonacci grid the
    largest chordal circumradius is 0.12051 (0.12058 rad), rounded up to 0.1206
    (tests/test_validate_polarized.py recomputes it with scipy's ConvexHull).  The test has a
    relative slack of 1e-12 of the entries' size, far above float64 round-off of g.  A Jones
    (non-depolarizing) matrix has g ≡ 0 and is always searched; a depolarizing one is often
    certified."""
    shape = m.shape[:-2]
    mm = m.reshape(-1, 4, 4)
    val = np.zeros(len(mm))
    best = np.zeros((len(mm), 3))
    best[:, 2] = 1.0
    live = np.flatnonzero(np.any(mm != 0, axis=(1, 2)))
    if live.size:
        # equal matrices are searched once (a delta lobe's matrix depends on wi alone, a
        # constant IOR gives every wavelength the same one)
        mv, inverse = np.unique(mm[live].reshape(-1, 16), axis=0, return_inverse=True)
        mv = mv.reshape(-1, 4, 4)
        inverse = inverse.reshape(-1)
        grid = fibonacci(GRID)
        s = np.concatenate([np.ones((GRID, 1)), grid], axis=1)[None]
        g = _g(mv, s)                                          # (n, K)
        n = len(mv)
        # the local search starts from the STARTS best grid points of each matrix
        k = np.argsort(g, axis=1)[:, :STARTS]                  # (n, S)
        b = grid[k]                                            # (n, S, 3)
        v = np.take_along_axis(g, k, axis=1)                   # (n, S)
        # matrices whose grid minimum certifies a positive margin are not searched (their
        # random steps are still drawn, so every other matrix's search is unchanged)
        lip = np.linalg.norm(mv[:, 0, 1:], axis=1) + np.linalg.norm(mv[:, 1:, 1:], ord=2,
                                                                    axis=(1, 2))
        size = np.abs(mv[:, 0, 0]) + np.linalg.norm(mv[:, 1:, 0], axis=1) + lip
        search = np.flatnonzero(~(v[:, 0] - lip * COVER > 1e-12 * size))
        bs, vs, ms = b[search], v[search], mv[search]
        if search.size:
            step = 0.15
            rng = np.random.default_rng(7)
            for _ in range(40):
                cand = (bs[:, :, None, :]
                        + step * rng.normal(size=(n, STARTS, 6, 3))[search])
                cand /= np.linalg.norm(cand, axis=-1, keepdims=True)
                sc = np.concatenate([np.ones((len(search), STARTS * 6, 1)),
                                     cand.reshape(len(search), -1, 3)], axis=-1)
                gc = _g(ms, sc).reshape(len(search), STARTS, 6)
                j = np.argmin(gc, axis=2)                          # (n, S)
                gj = np.take_along_axis(gc, j[..., None], axis=2)[..., 0]
                cj = np.take_along_axis(cand, j[..., None, None], axis=2)[:, :, 0]
                better = gj < vs
                bs = np.where(better[..., None], cj, bs)
                vs = np.where(better, gj, vs)
                step *= 0.75
        b[search], v[search] = bs, vs
        j = np.argmin(v, axis=1)
        v, b = v[np.arange(n), j], b[np.arange(n), j]
        val[live], best[live] = v[inverse], b[inverse]
    return val.reshape(shape), best.reshape(shape + (3,))


_PAULI = [np.eye(2), np.diag([1.0, -1.0]), np.array([[0.0, 1.0], [1.0, 0.0]]),
          np.array([[0.0, -1j], [1j, 0.0]])]


#: B[i, j] = σ_i ⊗ σ_j* / 4: H = Σ_ij M_ij B[i, j].
_BASIS = np.array([[np.kron(a, b.conj()) / 4.0 for b in _PAULI] for a in _PAULI])


def coherency(m: np.ndarray) -> np.ndarray:
    """Cloude's coherency matrix of M (…, 4, 4): Hermitian (…, 4, 4), trace M00."""
    return np.einsum("...ij,ijkl->...kl", m.astype(complex), _BASIS)


def cloude_min_eig(m: np.ndarray) -> np.ndarray:
    """The smallest eigenvalue of the coherency matrix (≥ 0: a deterministic mixture)."""
    return np.linalg.eigvalsh(coherency(m))[..., 0]


JONES_A = np.array([[1, 0, 0, 1], [1, 0, 0, -1], [0, 1, 1, 0], [0, 1j, -1j, 0]])


def jones_to_mueller(j: np.ndarray) -> np.ndarray:
    """The Mueller matrix of a Jones matrix (2, 2), S = A (E ⊗ E*)."""
    return np.real(JONES_A @ np.kron(j, j.conj()) @ np.linalg.inv(JONES_A))


# ----------------------------------------------------------------------------- reciprocity
def _sign(x):
    return np.where(np.signbit(x), -1.0, 1.0)


def stokes_basis(d: np.ndarray) -> np.ndarray:
    """Mitsuba's ``mueller::stokes_basis``: ``coordinate_system(d).first`` (vector.h:118,
    Duff et al. 2017), in numpy, (N, 3)."""
    x, y, z = d[:, 0], d[:, 1], d[:, 2]
    sign = _sign(z)
    a = -1.0 / (sign + z)
    b = x * y * a
    return np.stack([x * x * a * _sign(z) + 1.0, b * _sign(z), -x * _sign(z)], axis=1)


def rotator(theta: np.ndarray) -> np.ndarray:
    """``mueller::rotator`` (mueller.h:164), (N, 4, 4)."""
    s, c = np.sin(2 * theta), np.cos(2 * theta)
    m = np.zeros(theta.shape + (4, 4))
    m[..., 0, 0] = m[..., 3, 3] = 1.0
    m[..., 1, 1] = m[..., 2, 2] = c
    m[..., 1, 2], m[..., 2, 1] = s, -s
    return m


def rotate_stokes_basis(forward, current, target) -> np.ndarray:
    """``mueller::rotate_stokes_basis`` (mueller.h:315), (N, 4, 4)."""
    cu = current / np.linalg.norm(current, axis=1, keepdims=True)
    ta = target / np.linalg.norm(target, axis=1, keepdims=True)
    dot = np.clip(np.sum(cu * ta, axis=1), -1.0, 1.0)
    # unit_angle: 2·asin(|a − b|/2) (accurate near 0 and π)
    half = lambda v: 2 * np.arcsin(np.minimum(np.linalg.norm(v, axis=1) / 2, 1.0))  # noqa: E731
    theta = np.where(dot < 0, np.pi - half(cu + ta), half(cu - ta))
    flip = np.sum(forward * np.cross(current, target), axis=1) < 0
    return rotator(np.where(flip, -theta, theta))


Q = np.diag([1.0, 1.0, -1.0, 1.0])


def reversed_matrix(m: np.ndarray, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """The matrix reciprocity predicts for eval_R(wo, wi) from m = eval_R(wi, wo) (both
    divided by their cosines), (N, C, 4, 4): R_out · Q mᵀ Q · R_inᵀ (module docstring)."""
    r_in = rotate_stokes_basis(-wi, stokes_basis(wi), stokes_basis(-wi))
    r_out = rotate_stokes_basis(wo, stokes_basis(-wo), stokes_basis(wo))
    qmq = Q @ np.swapaxes(m, -1, -2) @ Q
    return r_out[:, None] @ qmq @ np.swapaxes(r_in, -1, -2)[:, None]


#: Fibonacci directions of the Stokes criterion's first search ...
GRID = 512


#: ... and how many of the best of them its local search starts from.
STARTS = 3

#: The chordal covering radius of the :data:`GRID`-point Fibonacci grid, rounded up: every unit
#: vector lies this close to a grid point (:func:`stokes_margin` derives its use).
COVER = 0.1206


# ----------------------------------------------------------------------------- comparisons
#: Below this |M00| a matrix has no polarization state to compare (its intensity is 0).
TINY = 1e-30


def polarization_diff(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Per lane: max over wavelengths and entries of |a/a00 − b/b00|, the matrices' polarization
    parts (|M_ij/M00| ≤ 1 for a physical matrix).  M00 itself is the intensity topics'
    (``eval_pdf``, ``weight``, ``reciprocity``, with their conditioning and box search): a
    defect of the intensity fails there, not in a polarized topic too.  Both M00 = 0: 0; one of them 0, or a non-finite
    entry: NaN (not compared; counted in the rows' ``not_compared``)."""
    a00, b00 = np.abs(a[..., 0, 0]), np.abs(b[..., 0, 0])
    both = (a00 > TINY) & (b00 > TINY)
    na = a / np.where(both, a[..., 0, 0], 1.0)[..., None, None]
    nb = b / np.where(both, b[..., 0, 0], 1.0)[..., None, None]
    d = np.abs(na - nb).max(axis=(-1, -2))
    d = np.where(both, d, np.where((a00 <= TINY) & (b00 <= TINY), 0.0, np.nan))
    finite = np.all(np.isfinite(a), axis=(-1, -2)) & np.all(np.isfinite(b), axis=(-1, -2))
    return np.where(finite, d, np.nan).max(axis=-1)


def sensitivity(fn, wi, wo, value, r) -> np.ndarray:
    """Per lane: the largest change of fn's polarization part (:func:`polarization_diff`) over 4
    8-ulp moves of both directions."""
    n = len(wi)
    moved = fn(perturb(np.tile(wi, (4, 1)), r), perturb(np.tile(wo, (4, 1)), r))
    d = polarization_diff(np.tile(value, (4, 1, 1, 1)), moved)
    return np.nan_to_num(d, nan=0.0).reshape(4, n).max(axis=0)
