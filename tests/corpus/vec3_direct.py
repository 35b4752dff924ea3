"""vec3_direct -- a one-bounce direct-illumination integrator written as a plain
``mi.SamplingIntegrator`` subclass, returning its radiance as ``mi.Vector3f``.

Style: research/teaching code; ``sample(self, scene, sampler, ray, medium, active)``
with ``active`` positional WITHOUT a default; the radiance is accumulated in an
``mi.Spectrum`` and returned as ``mi.Vector3f(L)`` (Mitsuba 3.9.1 accepts it for
RGB variants); no AOVs (``aov_names`` not defined); neither ``traverse`` nor
``to_string``.

CONTROL (correct): emitted radiance at the first hit (area emitter or, for an
escaped ray, the environment) + one emitter sample and one BSDF sample at the first
hit, combined with the power heuristic; delta lobes are handled by BSDF sampling
alone.  Equivalent to Mitsuba's ``path`` with ``max_depth = 2`` (and ``direct`` with
one emitter and one BSDF sample).
"""

import drjit as dr
import mitsuba as mi


def _power_heuristic(a, b):
    a2, b2 = dr.square(a), dr.square(b)
    w = a2 / (a2 + b2)
    return dr.select(dr.isfinite(w), w, 0.0)


class Vec3Direct(mi.SamplingIntegrator):
    def __init__(self, props):
        mi.SamplingIntegrator.__init__(self, props)

    def sample(self, scene, sampler, ray, medium, active):
        ray = mi.Ray3f(ray)
        ctx = mi.BSDFContext()

        si = scene.ray_intersect(ray, active)
        valid = si.is_valid() | (scene.environment() is not None)

        # Directly visible emitters (area lights, or the environment on a miss)
        L = mi.Spectrum(si.emitter(scene, active).eval(si, active))

        active = active & si.is_valid()
        bsdf = si.bsdf(ray)

        # ---- emitter sampling
        active_em = active & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth)
        ds, em_weight = scene.sample_emitter_direction(si, sampler.next_2d(active_em),
                                                       True, active_em)
        active_em &= ds.pdf != 0.0
        f, pdf_bsdf = bsdf.eval_pdf(ctx, si, si.to_local(ds.d), active_em)
        mis = dr.select(ds.delta, 1.0, _power_heuristic(ds.pdf, pdf_bsdf))
        L += dr.select(active_em, f * em_weight * mis, 0.0)

        # ---- BSDF sampling
        bs, bsdf_weight = bsdf.sample(ctx, si, sampler.next_1d(active),
                                      sampler.next_2d(active), active)
        delta = mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta)
        ray2 = si.spawn_ray(si.to_world(bs.wo))
        si2 = scene.ray_intersect(ray2, active)
        emitter = si2.emitter(scene, active)
        ds2 = mi.DirectionSample3f(scene, si2, si)
        pdf_em = scene.pdf_emitter_direction(si, ds2, active & ~delta)
        mis = dr.select(delta, 1.0, _power_heuristic(bs.pdf, pdf_em))
        L += dr.select(active, bsdf_weight * emitter.eval(si2, active) * mis, 0.0)

        return mi.Vector3f(L), valid, []


mi.register_integrator('vec3_direct', lambda props: Vec3Direct(props))
