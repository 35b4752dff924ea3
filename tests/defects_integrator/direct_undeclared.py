"""Control: a correct direct-illumination integrator (emission seen, plus emitter sampling and
BSDF sampling combined by multiple importance sampling, power heuristic) that has no
``max_depth`` and declares no ``FIXED_DEPTH``: the validator measures its depth (2) with the
closed emitting enclosure at two albedos and judges every scene at it.
"""

import drjit as dr
import mitsuba as mi

NAME = "defect_direct_undeclared"


def mis(a, b):
    a2, b2 = a * a, b * b
    return dr.select(a2 + b2 > 0, a2 / (a2 + b2), 0.0)


class DirectUndeclared(mi.SamplingIntegrator):
    def sample(self, scene, sampler, ray, medium=None, active=True):
        ctx = mi.BSDFContext()
        ray = mi.Ray3f(ray)
        active = mi.Bool(active)
        si = scene.ray_intersect(ray, active)
        valid = si.is_valid() | (scene.environment() is not None)
        L = dr.select(active, si.emitter(scene, active).eval(si, active), 0.0)
        active &= si.is_valid()
        bsdf = si.bsdf(ray)
        act_em = active & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth)
        ds, em_weight = scene.sample_emitter_direction(si, sampler.next_2d(act_em), True, act_em)
        f, f_pdf = bsdf.eval_pdf(ctx, si, si.to_local(ds.d), act_em)
        w_em = dr.select(ds.delta, 1.0, mis(ds.pdf, f_pdf))
        L += dr.select(act_em & (ds.pdf != 0), w_em * f * em_weight, 0.0)
        bs, weight = bsdf.sample(ctx, si, sampler.next_1d(active), sampler.next_2d(active),
                                 active)
        si2 = scene.ray_intersect(si.spawn_ray(si.to_world(bs.wo)), active)
        ds2 = mi.DirectionSample3f(scene, si2, si)
        delta = mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta)
        em_pdf = scene.pdf_emitter_direction(si, ds2, active & ~delta)
        w_bsdf = dr.select(delta, 1.0, mis(bs.pdf, em_pdf))
        L += dr.select(active, w_bsdf * weight * si2.emitter(scene, active).eval(si2, active),
                       0.0)
        return L, valid, []


mi.register_integrator(NAME, lambda props: DirectUndeclared(props))
