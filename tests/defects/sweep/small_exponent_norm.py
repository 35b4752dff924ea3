"""Planted defect that fires only at small exponents: the Phong lobe's pdf normalization
(p+1)/(2π) is computed from max(p, 1) -- a guard an author added against p < 1 -- so for
0 ≤ p < 1 the pdf is (2)/(2π) cos^p α while sample() draws cos^p α with its true density
(p+1)/(2π) cos^p α: at p = 0 the pdf integrates to 2.  Correct for every p ≥ 1, including
the default p = 20.

A pure Phong lobe f = k_s (p+2)/(2π) cos^p α around the mirror direction (weight = eval/pdf,
so the weight identity holds and the error shows in the pdf's normalization and χ²).
"""

import drjit as dr
import mitsuba as mi


class SmallExponentNorm(mi.BSDF):
    PARAMETER_RANGES = {"ks": (0.0, 1.0), "exponent": (0.0, 1e3, (0.5, 1.0, 5.0))}

    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.ks = mi.Float(props.get("ks", 0.7))
        self.exponent = mi.Float(props.get("exponent", 20.0))
        dr.make_opaque(self.ks, self.exponent)   # values are kernel inputs
        glossy = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
        self.m_components = [glossy]
        self.m_flags = glossy

    def traverse(self, callback):
        callback.put("ks", self.ks, mi.ParamFlags.Differentiable)
        callback.put("exponent", self.exponent, mi.ParamFlags.Differentiable)

    def _lobe(self, si, wo):
        c = dr.clip(dr.dot(wo, mi.reflect(si.wi)), 0.0, 1.0)
        return dr.select(c > 0, dr.power(c, self.exponent), 0.0)

    def _ok(self, si, wo):
        return (mi.Frame3f.cos_theta(si.wi) > 0) & (mi.Frame3f.cos_theta(wo) > 0)

    def eval(self, ctx, si, wo, active=True):
        f = self.ks * (self.exponent + 2) * dr.inv_two_pi * self._lobe(si, wo)
        return dr.select(self._ok(si, wo), mi.Spectrum(f * mi.Frame3f.cos_theta(wo)), 0.0)

    def pdf(self, ctx, si, wo, active=True):
        norm = (dr.maximum(self.exponent, 1.0) + 1) * dr.inv_two_pi   # DEFECT below p = 1
        return dr.select(self._ok(si, wo), norm * self._lobe(si, wo), 0.0)

    def eval_pdf(self, ctx, si, wo, active=True):
        return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

    def sample(self, ctx, si, sample1, sample2, active=True):
        cos_a = dr.exp(dr.log(sample2.x) / (self.exponent + 1))
        sin_a = dr.safe_sqrt(1 - cos_a * cos_a)
        s, c = dr.sincos(dr.two_pi * sample2.y)
        bs = dr.zeros(mi.BSDFSample3f)
        bs.wo = mi.Frame3f(mi.reflect(si.wi)).to_world(mi.Vector3f(sin_a * c, sin_a * s, cos_a))
        bs.eta = 1.0
        bs.sampled_component = 0
        bs.sampled_type = +mi.BSDFFlags.GlossyReflection
        bs.pdf = self.pdf(ctx, si, bs.wo)
        ok = self._ok(si, bs.wo) & (bs.pdf > 0)
        weight = self.eval(ctx, si, bs.wo) / dr.select(ok, bs.pdf, 1.0)
        return bs, dr.select(ok, weight, 0.0)

    def to_string(self):
        return "SmallExponentNorm[]"


mi.register_bsdf("defect_small_exponent_norm", lambda props: SmallExponentNorm(props))
