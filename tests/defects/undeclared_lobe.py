"""Planted defect: one declared component that samples two lobes, a diffuse and a glossy one.

component_count() is 1 and flags(0) = DiffuseReflection | GlossyReflection, so every sample
reports component 0 with an honest sampled_type (DiffuseReflection or GlossyReflection): no
sampled_type lies outside the flags of its component.  But a context restricted to
component 0 cannot isolate either lobe, and sampled_component does not say which lobe was
drawn; Mitsuba's BSDFs declare one component per lobe (plastic, roughplastic, phong:
[diffuse, glossy]).  Values, pdf and weights are right (a diffuse + Phong mixture): only the
``component`` topic can see it.
"""

import drjit as dr
import mitsuba as mi


class UndeclaredLobe(mi.BSDF):
    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.kd = mi.Float(props.get("diffuse_reflectance", 0.5))
        self.ks = mi.Float(props.get("specular_reflectance", 0.3))
        self.exponent = mi.Float(props.get("exponent", 20.0))
        # DEFECT: two lobes in one component
        self.m_components = [mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.GlossyReflection
                             | mi.BSDFFlags.FrontSide]
        self.m_flags = self.m_components[0]

    def traverse(self, callback):
        callback.put("diffuse_reflectance", self.kd, mi.ParamFlags.Differentiable)
        callback.put("specular_reflectance", self.ks, mi.ParamFlags.Differentiable)

    def _weights(self, ctx):
        d = ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, 0)
        g = ctx.is_enabled(mi.BSDFFlags.GlossyReflection, 0)
        w_s = self.ks / (self.kd + self.ks) if (d and g) else mi.Float(1.0 if g else 0.0)
        return d, g, w_s

    def eval_pdf(self, ctx, si, wo, active=True):
        d, g, w_s = self._weights(ctx)
        cos_i, cos_o = mi.Frame3f.cos_theta(si.wi), mi.Frame3f.cos_theta(wo)
        ok = (cos_i > 0) & (cos_o > 0)
        cos_a = dr.clip(dr.dot(mi.reflect(si.wi), wo), 0.0, 1.0)
        lobe = dr.power(cos_a, self.exponent)
        value, pdf = mi.Float(0.0), mi.Float(0.0)
        if d:
            value += self.kd * dr.inv_pi
            pdf += (1.0 - w_s) * cos_o * dr.inv_pi
        if g:
            value += self.ks * (self.exponent + 2.0) * dr.inv_two_pi * lobe
            pdf += w_s * (self.exponent + 1.0) * dr.inv_two_pi * lobe
        return (dr.select(ok, mi.Spectrum(value * cos_o), 0.0), dr.select(ok, pdf, 0.0))

    def eval(self, ctx, si, wo, active=True):
        return self.eval_pdf(ctx, si, wo, active)[0]

    def pdf(self, ctx, si, wo, active=True):
        return self.eval_pdf(ctx, si, wo, active)[1]

    def sample(self, ctx, si, sample1, sample2, active=True):
        d, g, w_s = self._weights(ctx)
        bs = dr.zeros(mi.BSDFSample3f)
        if not (d or g):
            return bs, mi.Spectrum(0.0)
        glossy = (sample1 < w_s) if (d and g) else mi.Bool(g)
        # Phong lobe around the mirror direction: cos α = u^(1/(p+1)).
        cos_a = dr.power(sample2.x, 1.0 / (self.exponent + 1.0))
        sin_a = dr.safe_sqrt(1.0 - cos_a * cos_a)
        s, c = dr.sincos(dr.two_pi * sample2.y)
        local = mi.Vector3f(sin_a * c, sin_a * s, cos_a)
        wo_g = mi.Frame3f(mi.reflect(si.wi)).to_world(local)
        bs.wo = dr.select(glossy, wo_g, mi.warp.square_to_cosine_hemisphere(sample2))
        bs.eta = 1.0
        bs.sampled_type = dr.select(glossy, mi.UInt32(int(mi.BSDFFlags.GlossyReflection)),
                                    mi.UInt32(int(mi.BSDFFlags.DiffuseReflection)))
        bs.sampled_component = mi.UInt32(0)
        value, bs.pdf = self.eval_pdf(ctx, si, bs.wo, active)
        ok = bs.pdf > 0
        return bs, dr.select(ok, value / dr.select(ok, bs.pdf, 1.0), 0.0)

    def to_string(self):
        return "UndeclaredLobe[]"


mi.register_bsdf("defect_undeclared_lobe", lambda props: UndeclaredLobe(props))
