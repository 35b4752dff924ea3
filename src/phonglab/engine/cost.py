r"""What one sample of each pixel costs: the rays its ``path`` camera path casts.

Adaptive sampling (:mod:`phonglab.engine.adaptive`) spends samples where the variance is; at
equal *time* what matters is variance per second, and the pixels with the most variance are
often those with the longest paths (glass, a lit object seen through bounces).  Mitsuba 3.9.1
reports no per-sample path length: ``path`` keeps its depth in a loop variable
(``src/integrators/path.cpp:317``, ``dr::masked(ls.depth, si.is_valid()) += 1``) and returns
only the radiance, and the ``aov`` integrator's ``depth`` AOV is the hit distance ``si.t``
(``src/integrators/aov.cpp:225``).  So phonglab counts them in its own loop,
:func:`path_casts`: the camera path of ``path.cpp`` with the same stopping rules — an escaped
ray ends it, a vertex continues while ``depth + 1 < max_depth`` (``path.cpp:225``), Russian
roulette from ``rr_depth`` with q = min(max(β)·η², 0.95) (``path.cpp:321–330``), β updated by
the BSDF sample weight — without evaluating emission or light samples, so its path lengths
have path.cpp's distribution.  It counts the rays cast: one intersection per vertex visited,
plus one shadow ray where ``path`` samples an emitter (a smooth BSDF at a vertex that may
continue).

**The model.**  A sample of pixel q costs ``c_q = a + s_q`` ray units, s_q the mean rays per
sample (:meth:`phonglab.engine.wavefront.Wavefront.cost_map`, from :data:`PROBE_SPP` probe samples per pixel, averaged over the
3×3 window) and a the cost of the rest of a sample (camera ray generation, the film's filter
splats, the per-pass work) in ray units, :data:`FIXED_COST` (docs/adaptive.md: how it was
fitted to timed passes over pixel groups, and how well it predicts them).

Sources: Mitsuba 3 ``src/integrators/path.cpp`` (the loop's stopping rules, read, not
copied); :mod:`phonglab.planner.ladder` (the same loop with the emission terms).
"""

from __future__ import annotations

import re

import drjit as dr
import mitsuba as mi

#: Probe samples per pixel of :meth:`~phonglab.engine.wavefront.Wavefront.cost_map`.
PROBE_SPP = 4
#: a of c = a + s: the cost of a sample besides its rays, in rays.
FIXED_COST = 0.25


def path_depths(integrator) -> tuple[int, int] | None:
    """(max_depth, rr_depth) of a ``path`` integrator (-1: unbounded), None for any other:
    its string form is the only place Mitsuba's Python side shows them
    (``path.cpp``, ``to_string``)."""
    if integrator is None or integrator.class_name() != "PathIntegrator":
        return None
    text = str(integrator)
    m, r = re.search(r"max_depth = (-?\d+)", text), re.search(r"rr_depth = (\d+)", text)
    if m is None or r is None:
        return None
    depth = int(m.group(1))
    return (-1 if depth < 0 or depth >= 2 ** 31 - 1 else depth), int(r.group(1))


@dr.syntax
def path_casts(scene, sampler, ray, max_depth: int, rr_depth: int):
    """Rays cast by ``path``'s camera path for each lane of ``ray`` (module docstring)."""
    ctx = mi.BSDFContext()
    ray = mi.Ray3f(ray)
    limit = mi.UInt32(0xFFFFFFFF if max_depth < 0 else max_depth)
    active = mi.Bool(max_depth != 0)
    depth, casts = mi.UInt32(0), mi.UInt32(0)
    beta, eta = mi.Spectrum(1.0), mi.Float(1.0)
    while active:
        si = scene.ray_intersect(ray, ray_flags=mi.RayFlags.All, coherent=(depth == 0),
                                 active=active)
        casts += 1
        more = si.is_valid() & (depth + 1 < limit)
        bsdf = si.bsdf(ray)
        casts += dr.select(more & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth), 1, 0)
        bs, weight = bsdf.sample(ctx, si, sampler.next_1d(), sampler.next_2d(), more)
        ray = si.spawn_ray(si.to_world(bs.wo))
        beta *= weight
        eta *= bs.eta
        depth[si.is_valid()] += 1
        beta_max = dr.max(mi.unpolarized_spectrum(beta))
        rr_prob = dr.minimum(beta_max * dr.square(eta), 0.95)
        rr_active = depth >= rr_depth
        beta[rr_active] *= dr.rcp(rr_prob)
        active = more & (~rr_active | (sampler.next_1d() < rr_prob)) & (beta_max != 0.0) \
            & (bs.pdf > 0)
    return casts
