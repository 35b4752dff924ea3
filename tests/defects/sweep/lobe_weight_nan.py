"""Planted defect that fires only at a parameter edge: the lobe-selection weight
k_s / (k_d + k_s) has no guard, so it is 0/0 = NaN when k_d = k_s = 0 (a black material).

A diffuse + Phong-lobe BSDF otherwise correct: f = k_d/π + k_s (p+2)/(2π) cos^p α, sampled as a
mixture with the selection weight w_s = k_s/(k_d + k_s), pdf the same mixture.  At every
other setting it is right; at k_d = k_s = 0 the pdf and the sample weight are NaN.
"""

import drjit as dr
import mitsuba as mi


class LobeWeightNan(mi.BSDF):
    PARAMETER_RANGES = {"kd": (0.0, 1.0), "ks": (0.0, 1.0), "exponent": (0.0, 1e3)}

    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.kd = mi.Float(props.get("kd", 0.4))
        self.ks = mi.Float(props.get("ks", 0.4))
        self.exponent = mi.Float(props.get("exponent", 20.0))
        dr.make_opaque(self.kd, self.ks, self.exponent)   # values are kernel inputs
        if props.get("kd", 0.4) + props.get("ks", 0.4) > 1.0:
            raise ValueError("kd + ks must not exceed 1")
        diffuse = mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide
        glossy = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
        self.m_components = [diffuse, glossy]
        self.m_flags = diffuse | glossy

    def traverse(self, callback):
        callback.put("kd", self.kd, mi.ParamFlags.Differentiable)
        callback.put("ks", self.ks, mi.ParamFlags.Differentiable)
        callback.put("exponent", self.exponent, mi.ParamFlags.Differentiable)

    def _lobe(self, si, wo):
        c = dr.clip(dr.dot(wo, mi.reflect(si.wi)), 0.0, 1.0)
        return dr.select(c > 0, dr.power(c, self.exponent), 0.0)

    def _w_s(self):
        return self.ks / (self.kd + self.ks)          # DEFECT: no guard for kd = ks = 0

    def _ok(self, si, wo):
        return (mi.Frame3f.cos_theta(si.wi) > 0) & (mi.Frame3f.cos_theta(wo) > 0)

    def _enabled(self, ctx):
        return (ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, 0),
                ctx.is_enabled(mi.BSDFFlags.GlossyReflection, 1))

    def eval(self, ctx, si, wo, active=True):
        diffuse, glossy = self._enabled(ctx)
        f = mi.Float(0.0)
        if diffuse:
            f += self.kd * dr.inv_pi
        if glossy:
            f += self.ks * (self.exponent + 2) * dr.inv_two_pi * self._lobe(si, wo)
        return dr.select(self._ok(si, wo), mi.Spectrum(f * mi.Frame3f.cos_theta(wo)), 0.0)

    def _weight(self, ctx):
        diffuse, glossy = self._enabled(ctx)
        return self._w_s() if diffuse and glossy else mi.Float(1.0 if glossy else 0.0)

    def pdf(self, ctx, si, wo, active=True):
        w = self._weight(ctx)
        p = ((1 - w) * mi.warp.square_to_cosine_hemisphere_pdf(wo)
             + w * (self.exponent + 1) * dr.inv_two_pi * self._lobe(si, wo))
        return dr.select(self._ok(si, wo), p, 0.0)

    def eval_pdf(self, ctx, si, wo, active=True):
        return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

    def sample(self, ctx, si, sample1, sample2, active=True):
        glossy = sample1 < self._weight(ctx)
        cos_a = dr.exp(dr.log(sample2.x) / (self.exponent + 1))
        sin_a = dr.safe_sqrt(1 - cos_a * cos_a)
        s, c = dr.sincos(dr.two_pi * sample2.y)
        lobe = mi.Frame3f(mi.reflect(si.wi)).to_world(mi.Vector3f(sin_a * c, sin_a * s, cos_a))
        bs = dr.zeros(mi.BSDFSample3f)
        bs.wo = dr.select(glossy, lobe, mi.warp.square_to_cosine_hemisphere(sample2))
        bs.eta = 1.0
        bs.sampled_component = dr.select(glossy, mi.UInt32(1), mi.UInt32(0))
        bs.sampled_type = dr.select(glossy, mi.UInt32(+mi.BSDFFlags.GlossyReflection),
                                    mi.UInt32(+mi.BSDFFlags.DiffuseReflection))
        bs.pdf = self.pdf(ctx, si, bs.wo)
        ok = self._ok(si, bs.wo) & (bs.pdf > 0)
        weight = self.eval(ctx, si, bs.wo) / dr.select(ok, bs.pdf, 1.0)
        return bs, dr.select(ok, weight, 0.0)

    def to_string(self):
        return "LobeWeightNan[]"


mi.register_bsdf("defect_lobe_weight_nan", lambda props: LobeWeightNan(props))
