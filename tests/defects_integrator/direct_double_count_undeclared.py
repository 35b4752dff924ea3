"""Planted defect: a direct-illumination integrator that adds emitter sampling and the
emitters its BSDF samples hit, both at full weight, instead of combining them by multiple
importance sampling.

Each strategy alone estimates the direct illumination; their sum estimates twice it wherever
a BSDF sample can hit an emitter (area lights, environments).  A point light cannot be hit by
a BSDF sample, so the plane under a point light is right; the closed emitting cube at depth 2
(Le + ρ Le) gets Le + 2ρ Le (bias).  Unlike direct_double_count.py it declares no ``FIXED_DEPTH``: the validator
measures its depth with the enclosure at two albedos, and no integer depth matches (at ρ = 0.5
it gives Le (1 + 2ρ) = 2 Le, the unbounded value; at ρ = 0.8 2.6 Le, between depths 3 and 4).
"""

import drjit as dr
import mitsuba as mi

NAME = "defect_direct_double_count_undeclared"


class DirectDoubleCountUndeclared(mi.SamplingIntegrator):

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
        f = bsdf.eval(ctx, si, si.to_local(ds.d), act_em)
        L += dr.select(act_em & (ds.pdf != 0), f * em_weight, 0.0)          # weight 1
        bs, weight = bsdf.sample(ctx, si, sampler.next_1d(active), sampler.next_2d(active),
                                 active)
        si2 = scene.ray_intersect(si.spawn_ray(si.to_world(bs.wo)), active)
        L += dr.select(active, weight * si2.emitter(scene, active).eval(si2, active), 0.0)
        # DEFECT: both strategies at weight 1 (no MIS): the direct light is counted twice
        return L, valid, []


mi.register_integrator(NAME, lambda props: DirectDoubleCountUndeclared(props))
