"""tut_delta -- a smooth-dielectric-like delta BSDF in the style of Mitsuba 3's
"custom BSDF in Python" tutorial.

Style: tutorial.  ``active`` is a positional parameter WITHOUT a default in every
method; ``eval`` and ``pdf`` return the Python float ``0.0`` and ``eval_pdf`` returns
the tuple ``(0.0, 0.0)`` (a pure delta BSDF has nothing to evaluate); flags are set
through ``self.m_flags`` / ``self.m_components``; ``to_string`` but no ``traverse``.

CONTROL (correct).  Reflection is chosen with the Fresnel probability, refraction
otherwise, so both sampled weights are 1.  The radiance-compression factor of a
refracted ray, eta_ti^2 (= 1/eta_it^2), is applied ONLY when ``ctx.mode`` is
``TransportMode.Radiance``; in ``TransportMode.Importance`` the transmitted weight
stays 1, as for Mitsuba's built-in ``dielectric``.  There is no tint.  Unlike the
tutorial it also honours ``ctx.is_enabled`` (type mask and component), so a context
that enables only one lobe gets that lobe with weight R (or T).
"""

import drjit as dr
import mitsuba as mi


class TutDelta(mi.BSDF):
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

        weight_t = t_i
        if ctx.mode == mi.TransportMode.Radiance:
            # Radiance is compressed/expanded when crossing the interface
            weight_t = weight_t * dr.square(eta_ti)

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
        return f'TutDelta[eta={self.eta}]'


mi.register_bsdf('tut_delta', lambda props: TutDelta(props))
