"""active_lambert -- a Lambertian BSDF written the way plugin authors write one after
reading the Mitsuba 3 tutorial.

Style: ``active`` positional WITHOUT a default in every method; the reflectance is read
with ``props.get_texture('reflectance', 0.5)`` so it accepts a plain float, an rgb, or a
nested ``<texture type="bitmap"/"uniform">``, and is evaluated with
``tex.eval(si, active)``; ``pdf`` returns an ``mi.Float``; flags set through
``self.m_flags`` / ``self.m_components``; has ``traverse`` (texture registered as an
object through ``callback.put``) and ``to_string``.

CONTROL (correct): f = rho/pi on the front side, cosine-weighted sampling, sample weight
rho.  Honours ``ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, 0)`` in eval, pdf and
sample (a context that masks the diffuse lobe out sees 0 everywhere).
"""

import drjit as dr
import mitsuba as mi


class ActiveLambert(mi.BSDF):
    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.reflectance = props.get_texture('reflectance', 0.5)
        self.m_components = [mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide]
        self.m_flags = self.m_components[0]

    def sample(self, ctx, si, sample1, sample2, active):
        cos_theta_i = mi.Frame3f.cos_theta(si.wi)
        bs = dr.zeros(mi.BSDFSample3f)

        if not ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, 0):
            return bs, mi.Color3f(0.0)

        active = active & (cos_theta_i > 0.0)
        bs.wo = mi.warp.square_to_cosine_hemisphere(sample2)
        bs.pdf = mi.warp.square_to_cosine_hemisphere_pdf(bs.wo)
        bs.eta = 1.0
        bs.sampled_type = mi.UInt32(+mi.BSDFFlags.DiffuseReflection)
        bs.sampled_component = mi.UInt32(0)

        value = self.reflectance.eval(si, active)
        active = active & (bs.pdf > 0.0)
        return bs, dr.select(active, value, 0.0)

    def eval(self, ctx, si, wo, active):
        if not ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, 0):
            return mi.Color3f(0.0)

        cos_theta_i = mi.Frame3f.cos_theta(si.wi)
        cos_theta_o = mi.Frame3f.cos_theta(wo)
        active = active & (cos_theta_i > 0.0) & (cos_theta_o > 0.0)

        value = self.reflectance.eval(si, active) * dr.inv_pi * cos_theta_o
        return dr.select(active, value, 0.0)

    def pdf(self, ctx, si, wo, active):
        if not ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, 0):
            return mi.Float(0.0)

        cos_theta_i = mi.Frame3f.cos_theta(si.wi)
        cos_theta_o = mi.Frame3f.cos_theta(wo)
        pdf = mi.warp.square_to_cosine_hemisphere_pdf(wo)
        return dr.select(active & (cos_theta_i > 0.0) & (cos_theta_o > 0.0), pdf, 0.0)

    def eval_pdf(self, ctx, si, wo, active):
        return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

    def traverse(self, callback):
        callback.put('reflectance', self.reflectance, mi.ParamFlags.Differentiable)

    def to_string(self):
        return f'ActiveLambert[\n  reflectance = {self.reflectance}\n]'


mi.register_bsdf('active_lambert', lambda props: ActiveLambert(props))
