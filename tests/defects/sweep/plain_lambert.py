"""An author-style Lambert with a plain-float ``kd`` and no PARAMETER_RANGES.

``author_lambert`` is correct: f = kd/π, albedo kd.  It accepts any kd at load time, so the
sweep probes kd up to 10⁴, where the albedo is 10⁴: advice (declare a range), not a fail.
``author_lambert_gain`` plants an energy defect inside the domain: f = 1.5 kd/π, albedo 1.2 at
its given kd = 0.8 -- a fail at the given point.
"""

import drjit as dr
import mitsuba as mi


class AuthorLambert(mi.BSDF):
    GAIN = 1.0

    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.kd = mi.Float(props.get("kd", 0.8 if self.GAIN != 1.0 else 0.5))
        self.m_components = [mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide]
        self.m_flags = self.m_components[0]

    def traverse(self, callback):
        callback.put("kd", self.kd, mi.ParamFlags.Differentiable)

    def _ok(self, si, wo):
        return (mi.Frame3f.cos_theta(si.wi) > 0) & (mi.Frame3f.cos_theta(wo) > 0)

    def eval(self, ctx, si, wo, active=True):
        value = self.GAIN * self.kd * dr.inv_pi * mi.Frame3f.cos_theta(wo)
        return dr.select(self._ok(si, wo), mi.Spectrum(value), 0.0)

    def pdf(self, ctx, si, wo, active=True):
        return dr.select(self._ok(si, wo), mi.warp.square_to_cosine_hemisphere_pdf(wo), 0.0)

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
        return bs, dr.select(self._ok(si, bs.wo) & (bs.pdf > 0), value, 0.0)

    def to_string(self):
        return "AuthorLambert[]"


class AuthorLambertGain(AuthorLambert):
    GAIN = 1.5                                                   # DEFECT: albedo 1.5 kd


mi.register_bsdf("author_lambert", lambda props: AuthorLambert(props))
mi.register_bsdf("author_lambert_gain", lambda props: AuthorLambertGain(props))
