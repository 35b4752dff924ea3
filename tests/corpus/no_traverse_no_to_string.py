"""no_traverse_no_to_string -- a minimal correct Lambertian BSDF, written the way a
first plugin often is: only the methods the renderer calls.

Style: minimal author plugin; defines NEITHER ``traverse`` NOR ``to_string`` (so
``mi.traverse`` finds no parameters and ``str()`` falls back to the default);
``active`` positional WITHOUT a default; reflectance read with
``props.get_texture('reflectance', 0.5)``; ``pdf`` returns a plain ``mi.Float``;
``m_flags``/``m_components`` set.

CONTROL (correct): f = rho/pi on the front side, cosine-weighted sampling, honours
``ctx.is_enabled(DiffuseReflection, 0)``.
"""

import drjit as dr
import mitsuba as mi


class NoTraverseNoToString(mi.BSDF):
    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.reflectance = props.get_texture('reflectance', 0.5)
        self.m_components = [mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide]
        self.m_flags = self.m_components[0]

    def _valid(self, ctx, si, wo, active):
        return (active & ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, 0)
                & (mi.Frame3f.cos_theta(si.wi) > 0.0)
                & (mi.Frame3f.cos_theta(wo) > 0.0))

    def eval(self, ctx, si, wo, active):
        valid = self._valid(ctx, si, wo, active)
        value = self.reflectance.eval(si, valid) * (dr.inv_pi * mi.Frame3f.cos_theta(wo))
        return dr.select(valid, value, 0.0)

    def pdf(self, ctx, si, wo, active):
        valid = self._valid(ctx, si, wo, active)
        return dr.select(valid, mi.Frame3f.cos_theta(wo) * dr.inv_pi, 0.0)

    def eval_pdf(self, ctx, si, wo, active):
        return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

    def sample(self, ctx, si, sample1, sample2, active):
        bs = dr.zeros(mi.BSDFSample3f)
        bs.wo = mi.warp.square_to_cosine_hemisphere(sample2)
        bs.eta = 1.0
        bs.sampled_type = mi.UInt32(+mi.BSDFFlags.DiffuseReflection)
        bs.sampled_component = mi.UInt32(0)
        bs.pdf = self.pdf(ctx, si, bs.wo, active)
        valid = bs.pdf > 0.0
        return bs, dr.select(valid, self.reflectance.eval(si, valid), 0.0)


mi.register_bsdf('no_traverse_no_to_string', lambda props: NoTraverseNoToString(props))
