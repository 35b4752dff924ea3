"""Planted defect: bs.pdf is a stale density (uniform hemisphere, 1/2π) while pdf() is right.

The sampler draws the cosine density that pdf() reports and the weight is eval/pdf(), so the
χ² test and the weight pass: only ``bs.pdf = pdf(bs.wo)`` sees it -- and MIS in a path tracer,
which uses bs.pdf, is biased (as blendbsdf's pdf was, mitsuba3 PR#1681).
"""

import drjit as dr
import mitsuba as mi


class StaleSamplePdf(mi.BSDF):
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
        return dr.select(self._ok(si, wo), mi.warp.square_to_cosine_hemisphere_pdf(wo), 0.0)

    def eval_pdf(self, ctx, si, wo, active=True):
        return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

    def sample(self, ctx, si, sample1, sample2, active=True):
        bs = dr.zeros(mi.BSDFSample3f)
        bs.wo = mi.warp.square_to_cosine_hemisphere(sample2)
        pdf = self.pdf(ctx, si, bs.wo)
        bs.pdf = dr.select(pdf > 0, dr.inv_two_pi, 0.0)                 # DEFECT: stale density
        bs.eta = 1.0
        bs.sampled_type = mi.UInt32(int(mi.BSDFFlags.DiffuseReflection))
        bs.sampled_component = mi.UInt32(0)
        value = self.eval(ctx, si, bs.wo) / dr.select(pdf > 0, pdf, 1.0)
        return bs, dr.select(pdf > 0, value, 0.0)

    def to_string(self):
        return "StaleSamplePdf[]"


mi.register_bsdf("defect_stale_sample_pdf", lambda props: StaleSamplePdf(props))
