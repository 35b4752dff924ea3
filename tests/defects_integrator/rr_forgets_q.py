"""Planted defect: Russian roulette without the 1/q reweighting of the surviving paths.

Unbiased Russian roulette divides the throughput of a surviving path by its survival
probability q; without it every path past ``rr_depth`` is weighted down, and the estimate
falls short of the infinite-depth value (the enclosure at ρ = 0.8, D = 64: bias).
Otherwise the control path tracer (path_control.py).
"""

import drjit as dr
import mitsuba as mi

NAME = "defect_rr_forgets_q"


def mis(a, b):
    """Power heuristic a² / (a² + b²), 0 where both are 0."""
    a2, b2 = a * a, b * b
    return dr.select(a2 + b2 > 0, a2 / (a2 + b2), 0.0)


class RRForgetsQ(mi.SamplingIntegrator):
    def __init__(self, props):
        mi.SamplingIntegrator.__init__(self, props)
        self.max_depth = int(props.get("max_depth", -1))
        self.rr_depth = int(props.get("rr_depth", 5))

    def sample(self, scene, sampler, ray, medium=None, active=True):
        ctx = mi.BSDFContext()
        ray = mi.Ray3f(ray)
        active = mi.Bool(active)
        L = mi.Spectrum(0.0)
        beta = mi.Spectrum(1.0)
        eta = mi.Float(1.0)
        prev_si = dr.zeros(mi.SurfaceInteraction3f)
        prev_pdf = mi.Float(1.0)
        prev_delta = mi.Bool(True)          # the camera ray: its emission is not MIS-weighted
        max_depth = self.max_depth if self.max_depth >= 0 else 1 << 30
        depth = 0
        valid = mi.Bool(False)
        while depth < max_depth and dr.any(active):
            si = scene.ray_intersect(ray, active)
            if depth == 0:
                valid = si.is_valid() | (scene.environment() is not None)
            # Emission found by the BSDF sample (or the camera ray), MIS against emitter sampling
            ds = mi.DirectionSample3f(scene, si, prev_si)
            em_pdf = scene.pdf_emitter_direction(prev_si, ds, active & ~prev_delta)
            w_bsdf = dr.select(prev_delta, 1.0, mis(prev_pdf, em_pdf))
            emitter = si.emitter(scene, active)
            L += dr.select(active, beta * w_bsdf * emitter.eval(si, active), 0.0)
            active &= si.is_valid()
            if depth + 1 >= max_depth:
                break
            bsdf = si.bsdf(ray)
            # Emitter sampling
            act_em = active & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth)
            ds, em_weight = scene.sample_emitter_direction(si, sampler.next_2d(act_em), True,
                                                           act_em)
            wo = si.to_local(ds.d)
            f, f_pdf = bsdf.eval_pdf(ctx, si, wo, act_em)
            w_em = dr.select(ds.delta, 1.0, mis(ds.pdf, f_pdf))
            L += dr.select(act_em & (ds.pdf != 0), beta * w_em * f * em_weight, 0.0)
            # BSDF sampling
            bs, weight = bsdf.sample(ctx, si, sampler.next_1d(active), sampler.next_2d(active),
                                     active)
            beta = dr.select(active, beta * weight, beta)
            eta = dr.select(active, eta * bs.eta, eta)
            prev_si = si
            prev_pdf = bs.pdf
            prev_delta = mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta)
            ray = si.spawn_ray(si.to_world(bs.wo))
            depth += 1
            # Russian roulette
            if depth >= self.rr_depth:
                q = dr.minimum(dr.max(beta) * eta * eta, 0.95)
                survive = sampler.next_1d(active) < q
                pass  # DEFECT: beta /= q forgotten
                active &= survive
            active &= dr.max(beta) > 0
            dr.schedule(L, beta, eta, ray, active, prev_si, prev_pdf, prev_delta, valid)
            sampler.schedule_state()
            dr.eval()
        return L, valid, []


mi.register_integrator(NAME, lambda props: RRForgetsQ(props))
