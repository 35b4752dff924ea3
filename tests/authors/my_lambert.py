"""A plugin author's Lambertian BSDF, correct: what `check --plugin`, `fit --plugin` and the notebook load.

"""

import drjit as dr
import mitsuba as mi


class MyLambert(mi.BSDF):
    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.reflectance = mi.Color3f(props.get("reflectance", 0.5))   # RGB variants
        self.m_components = [mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide]
        self.m_flags = self.m_components[0]

    def traverse(self, callback):
        callback.put("reflectance", self.reflectance, mi.ParamFlags.Differentiable)

    def _ok(self, si, wo, ctx=None):
        # a context that masks the diffuse lobe out (phonglab fit's per-lobe albedos) sees 0
        on = True if ctx is None else ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, 0)
        return on & (mi.Frame3f.cos_theta(si.wi) > 0) & (mi.Frame3f.cos_theta(wo) > 0)

    def eval(self, ctx, si, wo, active=True):
        value = self.reflectance * dr.inv_pi * mi.Frame3f.cos_theta(wo)
        return dr.select(self._ok(si, wo, ctx), mi.Spectrum(value), 0.0)

    def pdf(self, ctx, si, wo, active=True):
        return dr.select(self._ok(si, wo, ctx), mi.warp.square_to_cosine_hemisphere_pdf(wo), 0.0)

    def eval_pdf(self, ctx, si, wo, active=True):
        return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

    def sample(self, ctx, si, sample1, sample2, active=True):
        bs = dr.zeros(mi.BSDFSample3f)
        bs.wo = mi.warp.square_to_cosine_hemisphere(sample2)
        bs.pdf = self.pdf(ctx, si, bs.wo)
        bs.eta = 1.0
        bs.sampled_type = mi.UInt32(int(mi.BSDFFlags.DiffuseReflection))
        bs.sampled_component = mi.UInt32(0)
        value = self.eval(ctx, si, bs.wo) / dr.select(bs.pdf > 0, bs.pdf, 1.0)
        return bs, dr.select(bs.pdf > 0, value, 0.0)

    def to_string(self):
        return "MyLambert[]"


mi.register_bsdf("my_lambert", lambda props: MyLambert(props))
