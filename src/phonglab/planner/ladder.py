r"""The depth ladder: one path-traced render that gives the image at every candidate max_depth.

Mitsuba's ``path`` integrator at ``max_depth`` m adds, along one camera path, the emission
found at the vertices reached with fewer than m segments and the emitter samples taken at
vertices that may still continue (``depth + 1 < m``; ``src/integrators/path.cpp``, the loop
body: "Direct emission", "Emitter sampling", then BSDF sampling and Russian roulette).  Its
estimate at depth m is therefore a *prefix sum* of the contributions of one full-depth path,
provided the path's random decisions do not depend on m — which holds: the emitter and BSDF
samples and the roulette draw of segment k use the same sampler dimensions whatever m is, and
truncating at m only drops the terms after it.  :func:`ladder` (class ``DepthLadder``) traces
the full-depth path once (Russian roulette from ``rr_depth``, as ``path``) and returns,
besides the full image, one AOV group per depth d of ``DepthLadder.depths``: the sum of the
terms a depth-d render would keep.  One render (one JIT kernel, one set of samples) thus
replaces one render per depth of the planner's depth search (:mod:`.pilot`), and the difference D = full − depth-d is formed sample by
sample, exactly as two renders with the same seeds would give it.

The ladder also counts, over every sample it traces, the vertices its full-depth path found
(``DepthLadder.lengths``, one ``dr.scatter_reduce`` per sample into a small histogram):
:func:`work` turns them into the mean rays a ``path`` render casts per sample at any depth,
which the pilot uses to decide whether a shallower depth can save more than its search costs.

Each term is path.cpp's: emission at a hit weighted by the power-heuristic MIS weight against
emitter sampling from the previous vertex (weight 1 after a delta BSDF or at the camera), and the
emitter sample at a smooth vertex weighted against BSDF sampling (1 for a delta light).  The
per-depth images are equal *in distribution* to ``path`` renders at those depths (tested:
``tests/test_planner.py``), not bit for bit: the sampler dimensions are consumed in this loop's
order.  Scenes whose integrator hides emitters are left to the per-depth renders (the
``hide_emitters`` rule of area emitters seen through the first segment is not reproduced here).

Sources: Mitsuba 3 ``src/integrators/path.cpp`` and its Python rendition
``mitsuba/python/ad/integrators/prb.py`` (primal mode); Veach 1997, §9.2 (power heuristic).
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np


def _mis(pdf_a, pdf_b):
    """Power heuristic pdf_a² / (pdf_a² + pdf_b²), 0 where undefined."""
    a2, b2 = dr.square(pdf_a), dr.square(pdf_b)
    w = a2 / (a2 + b2)
    return dr.select(dr.isfinite(w), w, 0.0)


#: Bins of ``DepthLadder.lengths`` (vertices 0 .. LENGTH_BINS - 2, then "more").
LENGTH_BINS = 66

#: variant -> the DepthLadder class of that variant (mi.SamplingIntegrator is per variant)
_CLASSES: dict[str, type] = {}


def ladder_class() -> type:
    """The ``DepthLadder`` integrator class of the active variant (defined on first use)."""
    if mi.variant() not in _CLASSES:
        _CLASSES[mi.variant()] = _define()
    return _CLASSES[mi.variant()]


def _define() -> type:
    class DepthLadder(mi.SamplingIntegrator):
        """A full-depth path tracer that also returns the image truncated at each of ``depths``.

        Properties: ``depths`` (comma-separated positive ints, increasing), ``rr_depth`` (5).
        The AOVs are ``d<depth>.<channel>`` for each depth, channel in the film's order.
        """

        def __init__(self, props):
            super().__init__(props)
            self.depths = [int(s) for s in str(props.get("depths", "1")).split(",")]
            self.rr_depth = int(props.get("rr_depth", 5))
            self.channels = ["Y"] if mi.is_monochromatic else ["R", "G", "B"]
            #: lengths[k]: samples whose path found k surface vertices (the last bin: k or
            #: more), summed over every render with this integrator (:func:`work`)
            self.lengths = dr.zeros(mi.UInt32, LENGTH_BINS)

        def aov_names(self):
            return [f"d{d}.{c}" for d in self.depths for c in self.channels]

        @dr.syntax
        def sample(self, scene, sampler, ray, medium=None, active=True):
            ctx = mi.BSDFContext()
            ray = mi.Ray3f(ray)
            active = mi.Bool(active)
            depth = mi.UInt32(0)
            beta = mi.Spectrum(1.0)
            eta = mi.Float(1.0)
            total = mi.Spectrum(0.0)
            cum = [mi.Spectrum(0.0) for _ in self.depths]
            prev_si = dr.zeros(mi.SurfaceInteraction3f)
            prev_pdf = mi.Float(1.0)
            prev_delta = mi.Bool(True)
            valid = mi.Bool(False)
            while active:
                si = scene.ray_intersect(ray, ray_flags=mi.RayFlags.All, coherent=(depth == 0),
                                         active=active)
                valid |= active & (si.is_valid() | (depth > 0))
                # emission at this vertex: path of depth + 1 segments, kept by renders of m > depth
                ds = mi.DirectionSample3f(scene, si=si, ref=prev_si)
                em_pdf = scene.pdf_emitter_direction(prev_si, ds, ~prev_delta)
                le = beta * _mis(prev_pdf, em_pdf) * ds.emitter.eval(si, active & (prev_pdf > 0))
                le = dr.select(active, le, 0.0)
                total += le
                for i, d in enumerate(self.depths):
                    cum[i] += dr.select(depth < d, le, 0.0)
                go = active & si.is_valid()
                bsdf = si.bsdf(ray)
                active_em = go & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth)
                ds, em_w = scene.sample_emitter_direction(si, sampler.next_2d(), True, active_em)
                active_em &= ds.pdf != 0.0
                wo = si.to_local(ds.d)
                s1, s2 = sampler.next_1d(), sampler.next_2d()
                f_em, pdf_em = bsdf.eval_pdf(ctx, si, wo, active_em)
                bs, bsdf_w = bsdf.sample(ctx, si, s1, s2, go)
                lr = beta * f_em * em_w * dr.select(ds.delta, 1.0, _mis(ds.pdf, pdf_em))
                lr = dr.select(active_em, lr, 0.0)
                # emitter sample: path of depth + 2 segments, kept by renders of m > depth + 1
                total += lr
                for i, d in enumerate(self.depths):
                    cum[i] += dr.select(depth + 1 < d, lr, 0.0)
                ray = si.spawn_ray(si.to_world(bs.wo))
                beta *= bsdf_w
                eta *= bs.eta
                prev_si = mi.SurfaceInteraction3f(si)
                prev_pdf = bs.pdf
                prev_delta = mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta)
                depth[si.is_valid()] += 1
                beta_max = dr.max(mi.unpolarized_spectrum(beta))
                rr_prob = dr.minimum(beta_max * dr.square(eta), 0.95)
                rr_active = depth >= self.rr_depth
                beta[rr_active] *= dr.rcp(rr_prob)
                rr_go = sampler.next_1d() < rr_prob
                active = go & (~rr_active | rr_go) & (beta_max != 0.0) & (bs.pdf > 0)
            dr.scatter_reduce(dr.ReduceOp.Add, self.lengths, 1,
                              dr.minimum(depth, LENGTH_BINS - 1))
            aovs = []
            for c in cum:
                aovs += [c[0]] if mi.is_monochromatic else [c[0], c[1], c[2]]
            return total, valid, aovs

    return DepthLadder


def applies(info) -> bool:
    """True when ``DepthLadder`` (:func:`ladder_class`) can stand for the scene's ``path``
    integrator in the active variant: RGB or mono (AOVs are not converted from spectral samples, and a polarized
    path would carry Mueller matrices), and emitters not hidden."""
    hide = info.integrator_props.get("hide_emitters", "false").lower() == "true"
    return (mi.is_rgb or mi.is_monochromatic) and not mi.is_polarized and not hide


def ladder(depths, info):
    """A ``DepthLadder`` (:func:`ladder_class`) for ``depths`` keeping the scene's ``rr_depth``."""
    props = mi.Properties("depth_ladder")
    props["depths"] = ",".join(str(int(d)) for d in depths)
    if "rr_depth" in info.integrator_props:
        props["rr_depth"] = int(info.integrator_props["rr_depth"])
    return ladder_class()(props)


def work(lengths, depth: int) -> float:
    """Mean ray casts per sample of a ``path`` render at max_depth ``depth`` (-1: unbounded),
    from a ``DepthLadder.lengths`` histogram of full-depth paths: a path that found k
    vertices casts k + 1 rays (the last one escapes or is not cast when roulette ends it:
    counting it errs high), at most ``depth`` of them."""
    lengths = np.asarray(lengths, dtype=np.float64)
    casts = np.arange(1, len(lengths) + 1, dtype=np.float64)
    if depth > 0:
        casts = np.minimum(casts, depth)
    return float((lengths * casts).sum() / max(lengths.sum(), 1.0))


def split(passes_img, depths) -> tuple:
    """(full, {depth: images}) from the (P, H, W, C·(1 + len(depths))) passes of a ladder render."""
    c = 1 if mi.is_monochromatic else 3
    full = passes_img[..., :c]
    return full, {d: passes_img[..., c * (i + 1):c * (i + 2)] for i, d in enumerate(depths)}
