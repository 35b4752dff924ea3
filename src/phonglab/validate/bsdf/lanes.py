"""The lanes every topic probes: incidence cells, random directions and sample values.

One numpy array per quantity, all cells stacked (cell-major), so that a topic makes one
:mod:`phonglab.probe` call -- one kernel -- for the whole grid.  Random numbers come from
each topic's own stream (:data:`STREAMS`, :mod:`phonglab.validate.seeds`), so every topic is
reproducible on its own and independent of which other topics run.
"""

from __future__ import annotations

import mitsuba as mi
import numpy as np

from ... import probe
from ..directions import ONE_MINUS, sphere  # noqa: F401  (the lanes every topic draws)
from ..seeds import Streams

#: The BSDF topics' random streams (``weight`` and ``pdf`` check the same samples, drawn from
#: ``weight``'s).
STREAMS = Streams("bsdf", {
    "finite": 11, "eval_pdf": 12, "weight": 13, "chi2": 14, "energy": 15, "reciprocity": 16,
    "component": 17, "gradient": 18, "cost": 19, "normalization": 20,
    "eval_null_transmission": 21, "eval_diffuse_reflectance": 22,
    # the polarized topics (:mod:`.polarization`)
    "mueller": 23, "intensity": 24, "mueller_identities": 25, "mueller_reciprocity": 26})
#: ``rng(seed, topic)``: the generator of a topic's stream.
rng = STREAMS.rng


def exact(v: np.ndarray) -> np.ndarray:
    """Directions with |z| < 1e-12 snapped to z = 0 exactly (cos(π/2) is 6e-17 in floating point,
    which float32 keeps: the grazing cell must be cos θ = 0 itself)."""
    v = np.array(v, dtype=np.float64)
    flat = np.abs(v[..., 2]) < 1e-12
    v[..., 2] = np.where(flat, 0.0, v[..., 2])
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def incident(cells: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(wi (M·n, 3), cell index (M·n,)) for n lanes per (θ, φ) cell."""
    wi = exact(probe.direction(cells[:, 0], cells[:, 1]))
    return np.repeat(wi, n, axis=0), np.repeat(np.arange(len(cells)), n)


def special_wo(wi: np.ndarray) -> np.ndarray:
    """Directions every BSDF must survive, per wi row: mirror, straight through, grazing, normal.

    Returns (k, N, 3) for wi (N, 3).
    """
    mirror = wi * np.array([-1.0, -1.0, 1.0])
    through = -wi
    graze = exact(probe.direction(np.arccos(np.array([1e-4, 0.0, -1e-4])), 0.7))
    out = [mirror, through, np.broadcast_to([0.0, 0.0, 1.0], wi.shape),
           np.broadcast_to([0.0, 0.0, -1.0], wi.shape)]
    out += [np.broadcast_to(g, wi.shape) for g in graze]
    return np.stack(out)


def sample_values(r: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(u1 (n,), u2 (n, 2)): uniform, with the edge values 0 and 1 − ε in the first lanes."""
    u1, u2 = r.random(n), r.random((n, 2))
    edges = np.array([[0.0, 0.0, 0.0], [ONE_MINUS] * 3, [0.0, ONE_MINUS, 0.0],
                      [ONE_MINUS, 0.0, ONE_MINUS], [0.5, 0.0, 0.5], [0.5, ONE_MINUS, ONE_MINUS]])
    k = min(n, len(edges))
    u1[:k], u2[:k] = edges[:k, 0], edges[:k, 1:]
    return u1, u2


def delta_mask(sampled_type: np.ndarray) -> np.ndarray:
    """True where a sample's lobe is a delta (Dirac in 2D or 1D)."""
    bits = int(mi.BSDFFlags.Delta) | int(mi.BSDFFlags.Delta1D)
    return (sampled_type & bits) != 0


def every(mask: np.ndarray) -> np.ndarray:
    """Per row of a boolean (N, k) array: all k entries true -- ``np.all(mask, axis=1)``,
    column by column (numpy reduces a short row ~30x slower; these run on 10⁵-10⁶ samples)."""
    out = np.ones(len(mask), dtype=bool)
    for j in range(mask.shape[1]):
        out &= mask[:, j]
    return out


def some(mask: np.ndarray) -> np.ndarray:
    """Per row of a boolean (N, k) array: any entry true (``np.any(mask, axis=1)``, as
    :func:`every`)."""
    out = np.zeros(len(mask), dtype=bool)
    for j in range(mask.shape[1]):
        out |= mask[:, j]
    return out


def drawn(s: probe.Sample) -> np.ndarray:
    """The samples ``sample`` returned: weight ≠ 0 in some channel (Mitsuba marks a rejected
    sample with weight 0) and finite (:func:`finite_sample`; a NaN weight is not 0, but it is
    the ``finite`` topic's): the samples whose sampled_type and sampled_component the
    ``component`` topic judges."""
    return some(s.weight != 0) & finite_sample(s)


def counted(s: probe.Sample, black_at_wo: np.ndarray | None = None,
            finite: np.ndarray | None = None) -> np.ndarray:
    """The samples that carry a density (χ²'s histogram, the normalization count): not a delta
    lobe, finite (:func:`finite_sample`), and weight ≠ 0 in some channel (Mitsuba marks a
    rejected sample with weight 0).

    ``black_at_wo``: per sample, whether ``sample`` drew its wo inside the support where the
    BSDF is black (bs.pdf > 0, pdf(wi, wo) > 0, eval(wi, wo) = 0 in every channel); those
    count too, their weight 0 being the right value eval/pdf, not a rejection.  For a black
    cell that is χ²'s drawn-direction rule; it also covers a cell black in part (pplastic
    in a polarized variant at cos θ_i = 1e-4: 89 % of its diffuse samples have eval 0 there).
    ``finite``: :func:`finite_sample` of ``s``, when already computed.
    """
    carries = some(s.weight != 0)
    if black_at_wo is not None:
        carries |= black_at_wo
    return carries & ~delta_mask(s.sampled_type) & (finite_sample(s) if finite is None else finite)


def black_at_wo(bsdf, wi: np.ndarray, s: probe.Sample) -> np.ndarray:
    """Per sample of ``s`` (drawn at incidence ``wi``): weight 0, bs.pdf > 0 and a finite wo
    where the BSDF is black (pdf(wi, wo) > 0, eval(wi, wo) = 0 in every channel): the weight
    0 is the right value eval/pdf there, not a rejection (:func:`counted`)."""
    zero = ~some(s.weight != 0) & (s.pdf > 0) & every(np.isfinite(s.wo))
    black = np.zeros(len(zero), dtype=bool)
    if zero.any():
        ev, pd = probe.eval(bsdf, wi, s.wo[zero]), probe.pdf(bsdf, wi, s.wo[zero])
        black[zero] = (pd > 0) & np.all(ev == 0, axis=1)
    return black


def finite_sample(s: probe.Sample) -> np.ndarray:
    """Samples whose weight and wo are finite: a non-finite one is the ``finite`` topic's
    alone, and the other topics leave it out (of their counts and their totals)."""
    return every(np.isfinite(s.weight)) & every(np.isfinite(s.wo))


def bsdf_has(bsdf, flags) -> bool:
    """True when any component of ``bsdf`` has one of ``flags``."""
    return (int(bsdf.flags()) & int(flags)) != 0


def delta_only(bsdf) -> bool:
    """True when every component is a delta lobe (nothing to histogram or integrate)."""
    delta = int(mi.BSDFFlags.Delta) | int(mi.BSDFFlags.Delta1D)
    n = bsdf.component_count()
    return n > 0 and all(int(bsdf.flags(k)) & delta for k in range(n))
