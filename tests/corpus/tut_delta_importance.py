"""tut_delta_importance -- the tutorial-style smooth-dielectric delta BSDF of
``tut_delta`` with ONE bug.

Style: tutorial.  ``active`` positional WITHOUT a default; ``eval``/``pdf`` return the
Python float ``0.0`` and ``eval_pdf`` returns ``(0.0, 0.0)``; flags through
``self.m_flags`` / ``self.m_components``; ``to_string``, no ``traverse``.

BUG (one): the transmitted weight is multiplied by eta_ti^2 in BOTH transport modes,
as if ``TransportMode.Importance`` carried the radiance-compression factor too (the
tutorial's code does exactly this).  Radiance mode is right, so any render with
``path`` is unaffected; Importance mode (``ptracer``, light tracing, the adjoint
BSDF) is off by eta^2 per refraction.  Physical property broken: the adjoint
relation between the modes, f_Radiance(wi, wo)/|cos wo| = f_Importance(wo, wi)/|cos wi|
("importance"/mode reciprocity of a refracting interface).  Observed (eta 1.33): a
floor lit through ONE interface, 32x32, 64 spp: ``ptracer``/``path`` = 0.544 (built-in
``dielectric`` and ``tut_delta``: 0.963, Monte Carlo noise), i.e. light tracing is
1/eta^2 = 0.565 too dark.  Through a closed object (enter + exit) the two wrong factors
cancel, and ``path`` renders are bit-identical to ``dielectric``.
"""

import drjit as dr
import mitsuba as mi


class TutDeltaImportance(mi.BSDF):
    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        # Relative index of refraction of the interior w.r.t. the exterior
        self.eta = float(props.get('eta', 1.33))

        reflection = (mi.BSDFFlags.DeltaReflection | mi.BSDFFlags.FrontSide
                      | mi.BSDFFlags.BackSide)
        transmission = (mi.BSDFFlags.DeltaTransmission | mi.BSDFFlags.FrontSide
                        | mi.BSDFFlags.BackSide | mi.BSDFFlags.NonSymmetric)
        self.m_components = [reflection, transmission]
        self.m_flags = reflection | transmission

    def sample(self, ctx, si, sample1, sample2, active):
        cos_theta_i = mi.Frame3f.cos_theta(si.wi)
        r_i, cos_theta_t, eta_it, eta_ti = mi.fresnel(cos_theta_i, self.eta)
        t_i = dr.maximum(1.0 - r_i, 0.0)

        want_r = ctx.is_enabled(mi.BSDFFlags.DeltaReflection, 0)
        want_t = ctx.is_enabled(mi.BSDFFlags.DeltaTransmission, 1)

        # Probability of picking the reflected ray
        if want_r and want_t:
            prob_r = r_i
        elif want_r:
            prob_r = mi.Float(1.0)
        else:
            prob_r = mi.Float(0.0)

        take_r = sample1 < prob_r

        bs = mi.BSDFSample3f()
        bs.pdf = dr.select(take_r, prob_r, 1.0 - prob_r)
        bs.sampled_component = dr.select(take_r, mi.UInt32(0), mi.UInt32(1))
        bs.sampled_type = dr.select(take_r,
                                    mi.UInt32(+mi.BSDFFlags.DeltaReflection),
                                    mi.UInt32(+mi.BSDFFlags.DeltaTransmission))
        bs.wo = dr.select(take_r, mi.reflect(si.wi),
                          mi.refract(si.wi, cos_theta_t, eta_ti))
        bs.eta = dr.select(take_r, 1.0, eta_it)

        # Radiance is compressed/expanded when crossing the interface
        weight_t = t_i * dr.square(eta_ti)

        value = dr.select(take_r, r_i, weight_t) / dr.select(bs.pdf > 0, bs.pdf, 1.0)
        ok = active & (bs.pdf > 0) & (want_r or want_t)
        return bs, dr.select(ok, mi.Color3f(value), mi.Color3f(0.0))

    def eval(self, ctx, si, wo, active):
        return 0.0

    def pdf(self, ctx, si, wo, active):
        return 0.0

    def eval_pdf(self, ctx, si, wo, active):
        return 0.0, 0.0

    def to_string(self):
        return f'TutDeltaImportance[eta={self.eta}]'


mi.register_bsdf('tut_delta_importance', lambda props: TutDeltaImportance(props))
