r"""The ``chi2`` topic: does ``sample_direction`` draw directions with the density
``pdf_direction`` reports, seen from each reference point?

From each reference point p (:func:`~.setup.ref_groups`, the groups marked ``chi2``) N
directions are drawn; those with a non-zero weight are histogrammed over (φ, cos θ) in a frame
whose z axis points from p to the centre of the emitter's bounding box (an environment: the
world's z).  cos θ spans [c₀, 1]: c₀ = √(1 − (R/|p − c|)²) where p lies outside the bounding
sphere (centre c, radius R) of the shape -- no direction that leaves it can reach the emitter,
so the domain loses nothing -- and −1 elsewhere; φ spans [−π, π].  Bins are equal in
(φ, cos θ), i.e. in solid angle (dω = dφ d cos θ).  The expected count of a bin is
N ∫_bin pdf_direction dω:

* surface emitters: over the shape's surface (:func:`area_integrals`: dω = |cos θ'| dA/dist²,
  a shifted Fibonacci lattice on the shape's own sample_position parametrization, each node
  added to its direction's bin, only nodes that are the first hit of the ray from p), where
  the integrand stays bounded at a silhouette (an area-sampled pdf grows as 1/|cos θ'| there:
  a midpoint rule over directions missed a cylinder's sides by 30 %); pdf_direction is
  evaluated on a DirectionSample3f of the surface point, as an integrator's BSDF-sampled ray
  would give it;
* environments: the midpoint rule on ``chi2_ires``² nodes per bin, again on (4·ires)² in the
  bins where the nodes disagree (:func:`bin_integrals`), pdf_direction from the direction
  alone.

Pearson's χ² statistic over the bins (:func:`phonglab.stats.pearson_chi2` with
``pooling="one"``: bins with expected count < 5 pooled into one, merged into the smallest
remaining bin when the pool is itself < 5), p-value from the χ² distribution with (cells − 1)
degrees of freedom; each reference point is one test at the Šidák level of the emitter's m
statistical tests (:func:`~phonglab.stats.sidak`).  The emitter's (cos θ, φ) lattice has no
re-integration of slivers, so a sample in a bin whose quadrature found 0 is pooled rather than
impossible (the BSDF and phase-function topics' running pooling rejects it, after
:mod:`phonglab.validate.sphere_bins` re-integrates such bins).  A reference point whose histogram is empty while
∫pdf > 0 fails; one where both are empty (the back of a one-sided emitter) is not tested.
``mi.chi2.EmitterAdapter`` (mitsuba/python/chi2.py) samples from one zero Interaction3f and drops the weight; here every
reference point is its own test and a sample counts only when its weight is not 0 (an emitter
that emits nothing, every weight 0, has its samples counted where pdf_direction > 0).

Delta emitters have no density: for a delta-position light every ds.d must point from the
reference point at the light's position (ds.d = (P − p)/|P − p|, ds.dist = |P − p|), for a
directional light ds.d must be the same at every reference point; to :data:`DIRECTION_TOL`
per component (float32 normalisation is good to ~1e-6) and relatively for dist.
"""

from __future__ import annotations

import functools
import math

import mitsuba as mi
import numpy as np

from ... import probe, stats
from . import lanes as lanes_
from .identities import bounded, lane_inputs
from ..directions import basis
from .config import STREAMS
from .setup import Setup, float_, interaction, point2, ref_groups
from .topics import Row

#: Tolerance of a delta light's direction, per component of the unit vector.
DIRECTION_TOL = 1e-4
def frame(setup: Setup, p: np.ndarray) -> tuple[np.ndarray, float]:
    """(basis rows s, t, n, c₀): the histogram frame at p and the lowest cos θ it spans."""
    if setup.kind == "infinite":
        return np.eye(3), -1.0
    v = setup.center - p
    dist = float(np.linalg.norm(v))
    if dist <= setup.radius * 1.0001:
        z = v / dist if dist > 1e-6 else np.array([0.0, 0.0, 1.0])
        c0 = -1.0
    else:
        z = v / dist
        c0 = math.sqrt(max(0.0, 1.0 - (setup.radius / dist) ** 2)) - 1e-3
    return basis(z), max(-1.0, c0)


def _pdf_at(setup: Setup, p: np.ndarray, d: np.ndarray) -> np.ndarray:
    """pdf_direction from p towards each direction d (traced to the shape)."""
    return lanes_.pdf_towards(setup, np.tile(p, (len(d), 1)), d)


def _midpoint(setup, p, basis_, c_lo, c_hi, p_lo, p_hi, k) -> np.ndarray:
    """Midpoint-rule integrals of pdf_direction over bins (c_lo..c_hi) x (p_lo..p_hi) (arrays
    of B bins), k x k nodes each, and the node values: ((B,), (B, k, k))."""
    t = (np.arange(k) + 0.5) / k
    C = c_lo[:, None, None] + (c_hi - c_lo)[:, None, None] * t[None, :, None]
    P = p_lo[:, None, None] + (p_hi - p_lo)[:, None, None] * t[None, None, :]
    C, P = np.broadcast_arrays(C, P)
    s = np.sqrt(np.maximum(0.0, 1.0 - C * C))
    loc = np.stack([s * np.cos(P), s * np.sin(P), C], axis=-1).reshape(-1, 3)
    values = _pdf_at(setup, p, loc @ basis_).reshape(C.shape)
    area = (c_hi - c_lo) * (p_hi - p_lo) / (k * k)
    return values.sum(axis=(1, 2)) * area, values


#: Levels of 2 x 2 subdivision :func:`_refine` may add below the (4k)² rule of a rough bin.
MAX_SPLITS = 8
#: Two levels agree when they differ by at most this share of the bin's Poisson error.
POISSON_SHARE = 0.02


def _refine(setup, p, basis_, c_lo, c_hi, p_lo, p_hi, k, coarse, n, level=0) -> np.ndarray:
    """The integrals of bins whose k x k midpoint rule gave ``coarse``, each as the sum of its
    2 x 2 sub-bins' k x k rules, recursively wherever the two levels differ by more than
    POISSON_SHARE of the bin's Poisson error sqrt(N I)/N (N = ``n`` samples): a feature far
    smaller than a bin (sunsky's 0.53 deg sun) is integrated to its edge, not to a node's."""
    if len(coarse) == 0 or level >= MAX_SPLITS:
        return coarse
    cm, pm = 0.5 * (c_lo + c_hi), 0.5 * (p_lo + p_hi)
    kids = [(c_lo, cm, p_lo, pm), (c_lo, cm, pm, p_hi), (cm, c_hi, p_lo, pm), (cm, c_hi, pm, p_hi)]
    parts = np.stack([np.concatenate([_midpoint(setup, p, basis_, a[i:i + 256], b[i:i + 256],
                                                c[i:i + 256], d[i:i + 256], k)[0]
                                      for i in range(0, len(a), 256)])
                      for a, b, c, d in kids], axis=1)
    fine = parts.sum(axis=1)
    tol = POISSON_SHARE * np.sqrt(np.maximum(np.abs(fine), 1.0 / n) / n)
    bad = np.flatnonzero(np.abs(fine - coarse) > tol)
    if len(bad):
        for j, (a, b, c, d) in enumerate(kids):
            parts[bad, j] = _refine(setup, p, basis_, a[bad], b[bad], c[bad], d[bad], k,
                                    parts[bad, j], n, level + 1)
        fine[bad] = parts[bad].sum(axis=1)
    return fine


def bin_integrals(setup, p, basis_, c0, nc, nphi, k, n=None, peaks=None) -> np.ndarray:
    """∫_bin pdf_direction dω for the (nc, nphi) bins of [c0, 1] x [−π, π]: the midpoint rule
    on k x k nodes, and on (4k)² nodes in the bins where the nodes disagree (a bin holding the
    emitter's silhouette, where pdf jumps to 0, a dark bin beside a lit one, which the
    silhouette may cut between its nodes, or where pdf varies by more than 1.5x, or -- with
    ``peaks``, the (nc, nphi) largest ds.pdf of the samples in each bin -- where a sample
    saw a density above 1.5x all of the bin's nodes: a feature between them); with ``n``
    (the χ² sample count) those bins are then subdivided until two levels agree
    (:func:`_refine`)."""
    ce = np.linspace(c0, 1.0, nc + 1)
    pe = np.linspace(-np.pi, np.pi, nphi + 1)
    ci, pi = np.meshgrid(np.arange(nc), np.arange(nphi), indexing="ij")
    ci, pi = ci.ravel(), pi.ravel()
    integral, values = _midpoint(setup, p, basis_, ce[ci], ce[ci + 1], pe[pi], pe[pi + 1], k)
    lo, hi = values.min(axis=(1, 2)), values.max(axis=(1, 2))
    lit = (hi > 0).reshape(nc, nphi)
    near = lit.copy()                         # a bin beside a lit one (φ wraps around)
    near[1:] |= lit[:-1]
    near[:-1] |= lit[1:]
    near |= np.roll(lit, 1, axis=1) | np.roll(lit, -1, axis=1)
    between = np.zeros(nc * nphi, bool) if peaks is None else np.ravel(peaks) > 1.5 * hi
    rough = np.flatnonzero(((lo <= 0) & (hi > 0)) | (hi > 1.5 * lo) | (near & ~lit).ravel()
                           | between)
    for start in range(0, len(rough), 256):
        b = rough[start:start + 256]
        integral[b], _ = _midpoint(setup, p, basis_, ce[ci[b]], ce[ci[b] + 1], pe[pi[b]],
                                   pe[pi[b] + 1], 4 * k)
    if n is not None:
        b = rough
        integral[b] = _refine(setup, p, basis_, ce[ci[b]], ce[ci[b] + 1], pe[pi[b]],
                              pe[pi[b] + 1], 4 * k, integral[b], n)
    return integral.reshape(nc, nphi)


#: Consecutive Fibonacci numbers (F_m, F_{m−1}): the sizes and generators of the lattices.
FIBONACCI = {m: (a, b) for m, a, b in ((28, 317811, 196418), (30, 832040, 514229),
                                       (32, 2178309, 1346269))}


def fibonacci_lattice(m: int, shift) -> np.ndarray:
    """The Fibonacci lattice of F_m points in [0, 1)², u_i = (i/F_m, i F_{m−1}/F_m mod 1),
    shifted by ``shift`` modulo 1 (Cranley-Patterson): a rank-1 lattice whose discrepancy is
    O(log n / n), so the nodes a bin receives are its area to far better than a jittered grid's
    n^(−3/4), and it aligns with no axis of a shape's parametrization."""
    u = _fibonacci_unshifted(m) + np.asarray(shift)
    return np.fmod(u, 1.0, out=u)


@functools.lru_cache(maxsize=len(FIBONACCI))
def _fibonacci_unshifted(m: int) -> np.ndarray:
    """The lattice of :func:`fibonacci_lattice` before its shift (built once per m)."""
    n, g = FIBONACCI[m]
    i = np.arange(n, dtype=np.int64)
    u = np.stack([(i + 0.5) / n, ((i * g) % n + 0.5) / n], axis=1)
    u.flags.writeable = False
    return u


def area_integrals(setup, p, basis_, c0, nc, nphi, k, seed) -> np.ndarray:
    """∫_bin pdf_direction dω for a surface emitter, over its shape's surface instead: dω = |cos
    θ'| dA / dist², so ∫_bin pdf dω = ∫_{x visible, dir(x) ∈ bin} pdf(x) |cos θ'| / dist²
    dA, integrated on the shifted Fibonacci lattice of F_k nodes (:func:`fibonacci_lattice`,
    the shift from the seeded stream ``seed``) of the shape's own ``sample_position``
    parametrization (dA = du / p_A, independent of the emitter's sampling), each node added
    to the bin its direction falls in. Not a regular grid, which aliases with the bins (1024
    rows of a sphere's z = 1 − 2u into 24 bin rows give some bins 42 rows and others 43, 2.3
    % apart), nor jittered cells, whose node counts per bin scatter by 0.46 % (+14 on a χ²
    of 1151 degrees of freedom from an off-centre point inside a sphere, over 60 seeds). The
    integrand is smooth where the direction-space one is not: at a silhouette an
    area-sampled pdf grows as 1/|cos θ'| (a cylinder's sides), which a midpoint rule over
    directions misses by 30 % in the bins that hold it. A point counts where it is the first
    hit of the ray from p (the directions' own semantics)."""
    u = fibonacci_lattice(k, np.random.default_rng(seed).random(2))
    n = len(u)
    ps = setup.shape.sample_position(float_(np.zeros(n)), point2(u))
    x, p_area = probe.to_numpy(ps.p, n), probe.to_numpy(ps.pdf, n)
    v = x - p
    dist = np.sqrt(np.einsum("ij,ij->i", v, v))
    d = v / np.where(dist > 0, dist, 1.0)[:, None]
    at_p = np.broadcast_to(p, (n, 3))
    hit = lanes_.trace(setup, at_p, d)
    t_hit = probe.to_numpy(hit.t, n)
    visible = np.abs(t_hit - dist) <= 1e-4 * np.maximum(dist, setup.radius)
    # dω = |cos θ'| dA / dist² with the GEOMETRIC normal of the surface (si.n of the ray's own
    # hit, which is x where visible): ps.n is a mesh's interpolated vertex normal
    # (mesh.cpp:907), a shading normal, not the surface's orientation; only visible nodes
    # count, so the hit's normal is the only one needed
    geo_n = probe.to_numpy(hit.n, n)
    ds = mi.DirectionSample3f(ps)
    ds.d, ds.dist = probe.to_vectors(d), mi.Float(np.ascontiguousarray(dist, np.float32))
    ds.emitter = mi.EmitterPtr(setup.emitter)
    it = interaction(at_p)
    pdf = probe.to_numpy(setup.calls.pdf_direction(it, ds), n)
    cos = np.abs(np.einsum("ij,ij->i", d, geo_n))
    f = np.where(visible & np.isfinite(pdf) & (p_area > 0) & (dist > 0),
                 pdf * cos / np.maximum(dist, 1e-30) ** 2 / np.where(p_area > 0, p_area, 1.0),
                 0.0)
    local = d @ basis_.T
    ci = np.floor((local[:, 2] - c0) / (1.0 - c0) * nc).astype(int)
    pi = np.floor((np.arctan2(local[:, 1], local[:, 0]) + np.pi) / (2 * np.pi) * nphi)
    inside = ci >= 0                       # cos θ = 1 exactly falls in the last row
    ci, pi = np.clip(ci, 0, nc - 1), np.clip(pi.astype(int), 0, nphi - 1)
    out = np.bincount(ci * nphi + pi, weights=np.where(inside, f, 0.0), minlength=nc * nphi)
    return out.reshape(nc, nphi) / n


def emits(setup: Setup, points, seed, n: int = 4096) -> bool:
    """Whether any of ``n`` samples from any of ``points`` has a non-zero weight: False for an
    emitter that emits nothing (its radiance swept to 0)."""
    r = np.random.default_rng(seed)
    for p in points:
        it = interaction(np.tile(p, (n, 1)))
        _, w = setup.calls.sample_direction(it, point2(r.random((n, 2))))
        if np.any(probe.to_numpy(w, n) != 0):
            return True
    return False


def chi2_at(setup: Setup, p: np.ndarray, opts, level: float, seed: int,
            dark: bool = False) -> dict:
    """One χ² test from reference point p; its record (p-value, sums, verdict).  ``dark``: the
    emitter emits nothing anywhere (:func:`emits`), so its samples count where ds.pdf > 0."""
    basis_, c0 = frame(setup, p)
    n = opts.chi2_samples
    r = np.random.default_rng(seed)
    it = interaction(np.tile(p, (n, 1)))
    ds, w = setup.calls.sample_direction(it, point2(r.random((n, 2))))
    weight, pdf = probe.to_numpy(w, n), probe.to_numpy(ds.pdf, n)
    d = probe.to_numpy(ds.d, n)
    # an emitter that emits nothing (radiance swept to 0) still samples: its directions are
    # counted where pdf_direction, the expectation's integrand, is positive (the support a
    # lit emitter's non-zero weights mark: a one-sided area light's back has ds.pdf > 0 but
    # pdf_direction = 0); a sample outside that support is the `pdf` topic's to catch
    counts = (np.any(weight != 0, axis=1) if not dark else
              probe.to_numpy(setup.calls.pdf_direction(it, ds), n) > 0)
    keep = (np.all(np.isfinite(weight), axis=1) & counts
            & np.all(np.isfinite(d), axis=1) & (pdf > 0))
    occluded = 0
    if setup.kind == "surface" and keep.any():
        # the expectation counts a surface point only where it is the first hit of the ray
        # from p (area_integrals); a sample of a point behind another part of the shape (a
        # non-convex mesh, or one whose shading normals face p on its far side) is one an
        # integrator's shadow ray drops: it leaves the histogram too, and is counted
        dist = probe.to_numpy(ds.dist, n)
        t_hit = probe.to_numpy(lanes_.trace(setup, np.tile(p, (n, 1)),
                                            np.where(keep[:, None], d, [0.0, 0.0, 1.0])).t, n)
        hidden = keep & ~(np.abs(t_hit - dist) <= 1e-4 * np.maximum(dist, setup.radius))
        occluded, keep = int(hidden.sum()), keep & ~hidden
    local = d[keep] @ basis_.T
    cos, phi = np.clip(local[:, 2], -1.0, 1.0), np.arctan2(local[:, 1], local[:, 0])
    nc, nphi, k = opts.chi2_res, 2 * opts.chi2_res, opts.chi2_ires
    outside = int(np.sum(cos < c0))
    hist, _, _ = np.histogram2d(cos, phi, bins=(nc, nphi), range=((c0, 1.0), (-np.pi, np.pi)))
    if setup.kind == "surface":
        integral = area_integrals(setup, p, basis_, c0, nc, nphi, opts.chi2_area_nodes,
                                  [*np.atleast_1d(seed), 1])
    else:
        peaks = np.zeros(nc * nphi)             # the largest sampled ds.pdf per bin
        ci = np.clip(np.floor((cos - c0) / (1.0 - c0) * nc).astype(int), 0, nc - 1)
        pi = np.clip(np.floor((phi + np.pi) / (2 * np.pi) * nphi).astype(int), 0, nphi - 1)
        np.maximum.at(peaks, ci * nphi + pi, pdf[keep])
        integral = bin_integrals(setup, p, basis_, c0, nc, nphi, k, n, peaks)
    expected = n * integral
    rec = {"ref": p.tolist(), "c0": c0, "hist_sum": float(keep.sum()) / n,
           "pdf_sum": float(integral.sum()), "outside_domain": outside,
           "occluded": occluded / n, **({"dark": True} if dark else {})}
    if keep.sum() == 0 and integral.sum() < 1e-6:
        return {**rec, "status": "empty"}
    if keep.sum() == 0 or outside > 0:
        return {**rec, "status": "fail", "p_value": 0.0,
                "why": "no sample has a non-zero weight" if keep.sum() == 0 else
                f"{outside} samples lie outside the emitter's bounding sphere"}
    test = stats.pearson_chi2(hist, expected, pooling="one")
    stat, pv, dof = test.statistic, test.p_value, test.dof
    rec.update(p_value=pv, statistic=stat, dof=dof, status="pass" if pv >= level else "fail")
    if pv < level:
        rec["histogram"], rec["expected"] = hist.tolist(), expected.tolist()
    return rec


def chi2(setup: Setup, opts, m_tests: int) -> list[Row]:
    if setup.delta:
        return [delta_directions(setup, opts)]
    level = stats.sidak(stats.ALPHA, m_tests)
    groups = [g for g in ref_groups(setup, 1, opts.seed) if g.chi2]
    # whether it emits at all: the power topic's lanes
    dark = not emits(setup, [g.p[0] for g in groups], STREAMS.key(opts.seed, "power"))
    records = []
    for k, g in enumerate(groups):
        rec = chi2_at(setup, g.p[0], opts, level, seed=STREAMS.key(opts.seed, "chi2", k),
                      dark=dark)
        rec.update(group=g.label, where=g.where)
        sph = setup.sphere
        if sph is not None:
            rec["rel_radius"] = float(np.linalg.norm(g.p[0] - sph[0]) / sph[1] - 1.0)
        records.append(rec)
    tested = [r for r in records if r["status"] != "empty"]
    failed = [r for r in tested if r["status"] == "fail"]
    if not tested:
        return [Row("chi2", "direction sampling matches pdf_direction", None, None, None, None,
                    "skipped", "no reference point sees the emitter", {"points": records})]
    p_min = min(r["p_value"] for r in tested)
    reason = (f"Pearson χ² of sample_direction's directions vs pdf_direction over a "
              f"{opts.chi2_res}x{2 * opts.chi2_res} (cos θ, φ) histogram, {opts.chi2_samples} "
              f"samples, from {len(tested)} reference points, each at the Šidák level "
              f"{level:.2e} of the emitter's {m_tests} statistical tests (own Pearson χ², "
              f"to be merged with phonglab.stats')")
    if failed:
        reason += "; rejected from " + ", ".join(r["group"] for r in failed)
    row = Row("chi2", "direction sampling matches pdf_direction (min p-value)", p_min, level,
              None, level, "fail" if failed else "pass", reason,
              {"points": records, "level": level})
    row.failing_lanes = {"cell": failed} if failed else None
    return [row]


def delta_directions(setup: Setup, opts) -> Row:
    s = lanes_.sample(setup, opts, "chi2")
    live = s.live
    if setup.kind == "position":
        v = setup.center - s.p
        dist = np.linalg.norm(v, axis=1)
        err = np.maximum(np.max(np.abs(s.d - v / dist[:, None]), axis=1),
                         np.abs(s.dist - dist) / dist)
        what = "ds.d = (P − p)/|P − p| and ds.dist = |P − p| (relative) towards the light at P"
    else:
        ref = s.d[np.flatnonzero(live)[0]] if live.any() else np.zeros(3)
        err = np.max(np.abs(s.d - ref), axis=1)
        what = "ds.d the same at every reference point (a directional light)"
    err = np.where(live, err, 0.0)
    return bounded("chi2", "delta: sampled direction points at the light", err, DIRECTION_TOL,
                   f"a delta light has no density to histogram: max over {int(live.sum())} "
                   f"sampled lanes of the deviation from {what}; tolerance {DIRECTION_TOL:g}",
                   {"lanes": int(live.sum()), "light": setup.center.tolist()},
                   lane_inputs(setup, s, np.ones(s.n, bool)))
