"""Planted defect: pdf() reports 1.01 × the cosine density that sample() draws from.

bs.pdf is the same scaled value and the weight is eval / bs.pdf, so the weight, pdf and
eval_pdf identities all hold; every render is 1 % dark (the weight is 1/1.01 of what it
should be).  χ² sees the scale only through the normalization of the histogram, where it has
no power at these sizes; the normalization topic sees ∫ pdf dω_o = 1.01 against the
fraction of samples drawn (1: cosine sampling rejects nothing for cos θ_i > 0).
"""

import drjit as dr
import mitsuba as mi

#: DEFECT: the pdf's normalization is off by this factor.
SCALE = 1.01


class PdfScaled1Pct(mi.BSDF):
    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.reflectance = mi.Float(props.get("reflectance", 0.5))
        self.m_components = [mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide]
        self.m_flags = self.m_components[0]

    def traverse(self, callback):
        callback.put("reflectance", self.reflectance, mi.ParamFlags.Differentiable)

    def _ok(self, si, wo):
        return (mi.Frame3f.cos_theta(si.wi) > 0) & (mi.Frame3f.cos_theta(wo) > 0)

    def eval(self, ctx, si, wo, active=True):
        value = self.reflectance * dr.inv_pi * mi.Frame3f.cos_theta(wo)
        return dr.select(self._ok(si, wo), mi.Spectrum(value), 0.0)

    def pdf(self, ctx, si, wo, active=True):
        density = SCALE * mi.warp.square_to_cosine_hemisphere_pdf(wo)          # DEFECT
        return dr.select(self._ok(si, wo), density, 0.0)

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
        return "PdfScaled1Pct[]"


mi.register_bsdf("defect_pdf_scaled_1pct", lambda props: PdfScaled1Pct(props))
