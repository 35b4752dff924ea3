"""Planted defect: a Lambertian whose cos θ_i > 0 test was dropped from eval and pdf (but not
from sample).

Its flags declare a FrontSide lobe only (DiffuseReflection | FrontSide, as ``diffuse``), so
for ω_i below the surface an integrator expects eval = pdf = 0 and no sample.  Here eval and
pdf are ρ/π cos θ_o and cos θ_o/π there (∫pdf = 1) while sample() draws nothing: every
identity holds on the upper hemisphere, and MIS below the surface weighs emitter samples
against a density no BSDF sample realises.  Only the side-flag contract (the ``component``
topic's FrontSide row) can see it.
"""

import drjit as dr
import mitsuba as mi


class LitFromBelow(mi.BSDF):
    PARAMETER_RANGES = {"reflectance": (0.0, 1.0)}      # an albedo: the sweep stays physical

    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.reflectance = mi.Float(props.get("reflectance", 0.5))
        self.m_components = [mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide]
        self.m_flags = self.m_components[0]

    def traverse(self, callback):
        callback.put("reflectance", self.reflectance, mi.ParamFlags.Differentiable)

    def eval(self, ctx, si, wo, active=True):
        value = self.reflectance * dr.inv_pi * mi.Frame3f.cos_theta(wo)
        # DEFECT: no cos θ_i > 0 test (only cos θ_o > 0)
        return dr.select(mi.Frame3f.cos_theta(wo) > 0, mi.Spectrum(value), 0.0)

    def pdf(self, ctx, si, wo, active=True):
        # DEFECT: no cos θ_i > 0 test (only cos θ_o > 0)
        return dr.select(mi.Frame3f.cos_theta(wo) > 0,
                         mi.warp.square_to_cosine_hemisphere_pdf(wo), 0.0)

    def eval_pdf(self, ctx, si, wo, active=True):
        return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

    def sample(self, ctx, si, sample1, sample2, active=True):
        ok = mi.Frame3f.cos_theta(si.wi) > 0           # sample() keeps the test
        bs = dr.zeros(mi.BSDFSample3f)
        bs.wo = mi.warp.square_to_cosine_hemisphere(sample2)
        bs.pdf = dr.select(ok, mi.warp.square_to_cosine_hemisphere_pdf(bs.wo), 0.0)
        bs.eta = 1.0
        bs.sampled_type = mi.UInt32(int(mi.BSDFFlags.DiffuseReflection))
        bs.sampled_component = mi.UInt32(0)
        return bs, dr.select(ok & (bs.pdf > 0), mi.Spectrum(self.reflectance), 0.0)

    def to_string(self):
        return "LitFromBelow[]"


mi.register_bsdf("defect_lit_from_below", lambda props: LitFromBelow(props))
