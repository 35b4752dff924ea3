"""aov_depth -- a path tracer that also outputs a "depth" AOV, written as a plain
``mi.SamplingIntegrator`` subclass with the bounce loop UNROLLED in Python (a
``for`` loop over ``max_depth``, no ``dr.while_loop``), as simple research code does.

Style: ``aov_names()`` returns ``['depth']`` and ``sample`` returns
``(L, valid, [depth])``; ``active`` positional WITHOUT a default; ``max_depth`` from
``props.get('max_depth', 4)``; ``to_string`` present, no ``traverse``.

CONTROL (correct): next-event estimation + BSDF sampling with the power heuristic,
no Russian roulette, same depth convention as Mitsuba's ``path`` (max_depth 1 =
directly visible emitters only, 2 = direct illumination, ...), so the radiance
matches ``path`` (same max_depth, rr_depth > max_depth).  The AOV is the distance
along the camera ray to the first surface (``si.t``), 0 where the ray escapes --
the same quantity as Mitsuba's ``aov`` integrator's ``depth`` output.
"""

import drjit as dr
import mitsuba as mi


def _mis(a, b):
    a2, b2 = dr.square(a), dr.square(b)
    w = a2 / (a2 + b2)
    return dr.select(dr.isfinite(w), w, 0.0)


class AovDepth(mi.SamplingIntegrator):
    def __init__(self, props):
        mi.SamplingIntegrator.__init__(self, props)
        self.max_depth = int(props.get('max_depth', 4))

    def aov_names(self):
        return ['depth']

    def sample(self, scene, sampler, ray, medium, active):
        ctx = mi.BSDFContext()
        ray = mi.Ray3f(ray)
        L = mi.Spectrum(0.0)
        beta = mi.Spectrum(1.0)
        prev_si = dr.zeros(mi.Interaction3f)
        prev_pdf = mi.Float(1.0)
        prev_delta = mi.Bool(True)
        valid = mi.Bool(scene.environment() is not None) & active
        depth_aov = mi.Float(0.0)
        active = mi.Bool(active)

        for depth in range(self.max_depth):
            si = scene.ray_intersect(ray, active)
            if depth == 0:
                depth_aov = dr.select(si.is_valid(), si.t, 0.0)
                valid |= active & si.is_valid()

            # emission (area or environment) reached by the previous BSDF sample
            ds = mi.DirectionSample3f(scene, si, prev_si)
            pdf_em = scene.pdf_emitter_direction(prev_si, ds, active & ~prev_delta)
            w = dr.select(prev_delta, 1.0, _mis(prev_pdf, pdf_em))
            L += dr.select(active, beta * w * si.emitter(scene, active).eval(si, active), 0.0)

            if depth + 1 >= self.max_depth:
                break
            active = active & si.is_valid()
            bsdf = si.bsdf(ray)

            # next-event estimation
            active_em = active & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth)
            ds, em_w = scene.sample_emitter_direction(si, sampler.next_2d(active_em), True,
                                                      active_em)
            active_em &= ds.pdf != 0.0
            f, pdf_b = bsdf.eval_pdf(ctx, si, si.to_local(ds.d), active_em)
            w = dr.select(ds.delta, 1.0, _mis(ds.pdf, pdf_b))
            L += dr.select(active_em, beta * f * em_w * w, 0.0)

            # continue the path
            bs, bw = bsdf.sample(ctx, si, sampler.next_1d(active), sampler.next_2d(active),
                                 active)
            beta = dr.select(active, beta * bw, 0.0)
            ray = si.spawn_ray(si.to_world(bs.wo))
            prev_si = mi.Interaction3f(si)
            prev_pdf = bs.pdf
            prev_delta = mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta)
            active = active & (dr.max(beta) > 0.0)

        return L, valid, [depth_aov]

    def to_string(self):
        return f'AovDepth[max_depth={self.max_depth}]'


mi.register_integrator('aov_depth', lambda props: AovDepth(props))
