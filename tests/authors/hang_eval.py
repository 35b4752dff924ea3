"""Planted defect: eval never returns (a Python `while True`): `--timeout` makes its topics failing rows.

sample and pdf are a correct Lambertian, so the topics that call only them still pass.
"""

import drjit as dr
import mitsuba as mi


class HangEval(mi.BSDF):
    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.reflectance = mi.Float(props.get("reflectance", 0.5))
        self.m_components = [mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide]
        self.m_flags = self.m_components[0]

    def traverse(self, callback):
        callback.put("reflectance", self.reflectance, mi.ParamFlags.Differentiable)

    def _ok(self, si, wo):
        return (mi.Frame3f.cos_theta(si.wi) > 0) & (mi.Frame3f.cos_theta(wo) > 0)

    def _eval(self, si, wo):
        value = self.reflectance * dr.inv_pi * mi.Frame3f.cos_theta(wo)
        return dr.select(self._ok(si, wo), mi.Spectrum(value), 0.0)

    def eval(self, ctx, si, wo, active=True):
        while True:                                                   # DEFECT: never returns
            pass
        value = 0.0
        return dr.select(self._ok(si, wo), mi.Spectrum(value), 0.0)

    def pdf(self, ctx, si, wo, active=True):
        return dr.select(self._ok(si, wo), mi.warp.square_to_cosine_hemisphere_pdf(wo), 0.0)

    def eval_pdf(self, ctx, si, wo, active=True):
        return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)   # hangs too

    def sample(self, ctx, si, sample1, sample2, active=True):
        bs = dr.zeros(mi.BSDFSample3f)
        bs.wo = mi.warp.square_to_cosine_hemisphere(sample2)
        bs.pdf = self.pdf(ctx, si, bs.wo)
        bs.eta = 1.0
        bs.sampled_type = mi.UInt32(int(mi.BSDFFlags.DiffuseReflection))
        bs.sampled_component = mi.UInt32(0)
        value = self._eval(si, bs.wo) / dr.select(bs.pdf > 0, bs.pdf, 1.0)
        return bs, dr.select(bs.pdf > 0, value, 0.0)

    def to_string(self):
        return "HangEval[]"


mi.register_bsdf("defect_hang_eval", lambda props: HangEval(props))
