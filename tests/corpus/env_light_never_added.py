"""env_light_never_added -- a path tracer in the style of Mitsuba's differentiable
integrators (``mi.ad.integrators.common.RBIntegrator`` subclass -- 3.9.1 has no
``mi.ad.common`` attribute -- like ``prb_basic``), primal mode
only, with the bounce loop written as an explicit ``dr.while_loop`` whose state tuple
DOES carry the sampler.

Style: mi.ad.common / research code; ``sample(self, mode, scene, sampler, ray, δL,
state_in, active, **kwargs)`` (the extra 3.9.1 arguments ``depth``/``δaovs`` are
absorbed by ``**kwargs``), returns ``(L, valid, [], L)``; ``max_depth``/``rr_depth``
come from RBIntegrator's constructor; next-event estimation + BSDF sampling with the
power heuristic; ``to_string`` inherited, no ``traverse``.

BUG (one): the radiance found by a BSDF-sampled (or camera) ray is looked up as
``si.shape.emitter().eval(si)`` -- the emitter of the SHAPE that was hit -- instead of
``si.emitter(scene)``, which also returns the scene's environment emitter when the ray
escapes.  Area lights work; an ``envmap``/``constant`` emitter is never added on a miss.
Next-event estimation still samples the environment, so its light arrives only with
its MIS weight.  Physical property broken: unbiasedness (``bias``): the background
renders black and surfaces lit by the environment are too dark.

OBSERVED (32x32, 16 spp, diffuse 0.6 sphere on a diffuse floor, max_depth 4, vs
``path``): area light only: 0.0810 vs 0.0810 (identical); area light + constant env
0.3: 0.0867 vs 0.2758 (surfaces alone 0.130 vs 0.264, sky black); constant env 1.0
only: 0.0535 vs 0.6601 (surfaces 0.080 vs 0.490).
"""

import drjit as dr
import mitsuba as mi


def _mis(a, b):
    a2, b2 = dr.square(a), dr.square(b)
    w = a2 / (a2 + b2)
    return dr.select(dr.isfinite(w), w, 0.0)


class EnvLightNeverAdded(mi.ad.integrators.common.RBIntegrator):
    def __init__(self, props):
        super().__init__(props)

    def sample(self, mode, scene, sampler, ray, δL, state_in, active, **kwargs):
        if mode != dr.ADMode.Primal:
            raise NotImplementedError('env_light_never_added: primal rendering only')

        ctx = mi.BSDFContext()
        max_depth, rr_depth = self.max_depth, self.rr_depth

        def cond(sampler, ray, L, beta, depth, prev_si, prev_pdf, prev_delta, valid, active):
            return active

        def body(sampler, ray, L, beta, depth, prev_si, prev_pdf, prev_delta, valid, active):
            si = scene.ray_intersect(ray, active)

            ds = mi.DirectionSample3f(scene, si, prev_si)
            pdf_em = scene.pdf_emitter_direction(prev_si, ds, active & ~prev_delta)
            w = dr.select(prev_delta, 1.0, _mis(prev_pdf, pdf_em))
            Le = si.shape.emitter().eval(si, active & si.is_valid())
            L += dr.select(active, beta * w * Le, 0.0)

            valid |= active & si.is_valid()
            active_next = active & si.is_valid() & (depth + 1 < max_depth)
            bsdf = si.bsdf(ray)

            active_em = active_next & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth)
            ds, em_w = scene.sample_emitter_direction(si, sampler.next_2d(active_em), True,
                                                      active_em)
            active_em &= ds.pdf != 0.0
            f, pdf_b = bsdf.eval_pdf(ctx, si, si.to_local(ds.d), active_em)
            w = dr.select(ds.delta, 1.0, _mis(ds.pdf, pdf_b))
            L += dr.select(active_em, beta * f * em_w * w, 0.0)

            bs, bw = bsdf.sample(ctx, si, sampler.next_1d(active_next),
                                 sampler.next_2d(active_next), active_next)
            beta = dr.select(active_next, beta * bw, beta)
            ray = si.spawn_ray(si.to_world(bs.wo))
            prev_si = mi.Interaction3f(si)
            prev_pdf = bs.pdf
            prev_delta = mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta)
            depth = dr.select(active, depth + 1, depth)

            rr_prob = dr.minimum(dr.max(beta), 0.95)
            rr_on = depth >= rr_depth
            beta = dr.select(rr_on, beta / rr_prob, beta)
            survive = ~rr_on | (sampler.next_1d(active_next) < rr_prob)
            active = active_next & survive & (dr.max(beta) > 0.0)
            return sampler, ray, L, beta, depth, prev_si, prev_pdf, prev_delta, valid, active

        state = (sampler, mi.Ray3f(ray), mi.Spectrum(0.0), mi.Spectrum(1.0), mi.UInt32(0),
                 dr.zeros(mi.Interaction3f), mi.Float(1.0), mi.Bool(True),
                 mi.Bool(False), mi.Bool(active))
        state = dr.while_loop(state=state, cond=cond, body=body)
        L, valid = state[2], state[8]
        return L, valid, [], L


mi.register_integrator('env_light_never_added', lambda props: EnvLightNeverAdded(props))
