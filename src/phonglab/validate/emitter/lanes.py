"""The lanes of the identity topics: every reference group's points stacked, one
``sample_direction`` call for all of them, and the per-lane results as numpy arrays.

Sample values are uniform from the topic's seeded stream with the edges (0, 0), (1−ε, 1−ε),
(0, 1−ε), (1−ε, 0), (½, 0), (½, 1−ε) in the first lanes of every group (1−ε: the largest
float32 below 1).
"""

from __future__ import annotations

from dataclasses import dataclass

import drjit as dr
import mitsuba as mi
import numpy as np

from ... import probe
from ..directions import ONE_MINUS
from .config import rng
from .setup import RefGroup, Setup, interaction, point2, ref_groups, surface_interaction

#: 1 − ε for a float32 sample value: the largest float32 below 1.
EDGES = np.array([[0.0, 0.0], [ONE_MINUS, ONE_MINUS], [0.0, ONE_MINUS], [ONE_MINUS, 0.0],
                  [0.5, 0.0], [0.5, ONE_MINUS]])


def with_edges(u: np.ndarray, n: int) -> np.ndarray:
    """u (M·n, k) with :data:`EDGES` in the first lanes of each block of n (first 2 columns)."""
    u = np.array(u)
    k = min(n, len(EDGES))
    for start in range(0, len(u), n):
        u[start:start + k, :2] = EDGES[:k]
    return u


@dataclass
class Lanes:
    """``sample_direction`` at every reference lane: inputs and outputs as numpy arrays."""

    groups: list[RefGroup]
    group: np.ndarray      #: group index per lane
    p: np.ndarray          #: reference point (N, 3)
    u: np.ndarray          #: sample values (N, 2)
    it: object             #: the mi.Interaction3f
    ds: object             #: the mi.DirectionSample3f
    weight: np.ndarray     #: (N, C)
    pdf: np.ndarray
    d: np.ndarray
    dist: np.ndarray
    ds_p: np.ndarray
    ds_n: np.ndarray
    delta: np.ndarray

    @property
    def n(self) -> int:
        return len(self.p)

    @property
    def live(self) -> np.ndarray:
        """Lanes with a finite, non-zero weight and a finite pdf > 0 (a sample to check)."""
        w = self.weight
        return (np.all(np.isfinite(w), axis=1) & np.any(w != 0, axis=1)
                & np.isfinite(self.pdf) & (self.pdf > 0))


def sample(setup: Setup, opts, topic: str) -> Lanes:
    groups = ref_groups(setup, opts.n_lanes, opts.seed)
    n = opts.n_lanes
    p = np.concatenate([g.p for g in groups])
    group = np.repeat(np.arange(len(groups)), n)
    u = with_edges(rng(opts.seed, topic).random((len(p), 2)), n)
    it = interaction(p)
    ds, w = setup.calls.sample_direction(it, point2(u))
    N = len(p)
    return Lanes(groups, group, p, u, it, ds, probe.to_numpy(w, N), probe.to_numpy(ds.pdf, N),
                 probe.to_numpy(ds.d, N), probe.to_numpy(ds.dist, N), probe.to_numpy(ds.p, N),
                 probe.to_numpy(ds.n, N), np.array(probe.to_numpy(ds.delta, N), bool))


#: How far along its direction a traced ray starts (times the bounding radius): a reference
#: point on the surface must not hit itself (an integrator's spawn_ray offsets likewise).
TRACE_OFFSET = 1e-4


def trace(setup: Setup, p: np.ndarray, d: np.ndarray):
    """The shape's intersection of rays from p along d (started TRACE_OFFSET·R along d), in
    the scene that holds the shape alone; si.t is measured from p."""
    o = p + TRACE_OFFSET * setup.radius * d
    ray = mi.Ray3f(mi.Point3f(*(mi.Float(np.ascontiguousarray(o[:, k], np.float32))
                                for k in range(3))), probe.to_vectors(d), 0.0,
                   interaction(p).wavelengths)       # the reference lanes' wavelengths
    si = setup.scene.ray_intersect(ray)
    si.t = si.t + TRACE_OFFSET * setup.radius
    return si


def traced_radiance(setup: Setup, p: np.ndarray, d: np.ndarray):
    """(radiance (N, C), hit distance (N,)) that a ray from p along d sees of the emitter:
    ``emitter.eval`` at the shape's intersection (inf where the ray misses it), or for an
    environment at si.wi = −d (the convention of envmap.cpp's eval: v = to_world⁻¹(−si.wi))."""
    n = len(p)
    if setup.kind == "surface":
        si = trace(setup, p, d)
        valid = np.array(si.is_valid(), bool).reshape(-1)
        if valid.size == 1:
            valid = np.repeat(valid, n)
        value = probe.to_numpy(setup.calls.eval(si, si.is_valid()), n)
        t = np.where(valid, probe.to_numpy(si.t, n), np.inf)
        return value, t
    si = surface_interaction(n)
    si.wi = -probe.to_vectors(d)
    return probe.to_numpy(setup.calls.eval(si), n), np.full(n, np.inf)


def pdf_towards(setup: Setup, p: np.ndarray, d: np.ndarray) -> np.ndarray:
    """pdf_direction from each p towards d, its DirectionSample3f built from the shape's hit
    (``mi.DirectionSample3f(None, si, it)``, as an integrator's BSDF-sampled ray would), an
    environment's from the direction alone; non-finite values as 0."""
    n = len(d)
    it = interaction(p)
    if setup.kind == "surface":
        si = trace(setup, p, d)
        ds = mi.DirectionSample3f(None, si, it)
        ds.emitter = mi.EmitterPtr(setup.emitter)
        value = dr.select(si.is_valid(), setup.calls.pdf_direction(it, ds, si.is_valid()), 0.0)
    else:
        ds = dr.zeros(mi.DirectionSample3f, n)
        ds.d = probe.to_vectors(d)
        ds.dist = mi.Float(float("inf"))
        value = setup.calls.pdf_direction(it, ds)
    out = probe.to_numpy(value, n)
    return np.where(np.isfinite(out), out, 0.0)
