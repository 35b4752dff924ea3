"""Control: a depolarizing Lambertian, f = ρ/π with the Mueller matrix diag(ρ/π, 0, 0, 0)
(``mi.depolarizer``, as Mitsuba's diffuse.cpp).  It must pass every topic in every variant."""

import drjit as dr
import mitsuba as mi


class NanOffDiagonal(mi.BSDF):
    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.reflectance = mi.Float(props.get("reflectance", 0.5))
        self.m_components = [mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide]
        self.m_flags = self.m_components[0]

    def traverse(self, callback):
        callback.put("reflectance", self.reflectance, mi.ParamFlags.Differentiable)

    def _ok(self, si, wo):
        return (mi.Frame3f.cos_theta(si.wi) > 0) & (mi.Frame3f.cos_theta(wo) > 0)

    def _value(self, ctx, si, wo):
        f = mi.UnpolarizedSpectrum(self.reflectance * dr.inv_pi * mi.Frame3f.cos_theta(wo))
        if not mi.is_polarized:
            return mi.Spectrum(f)
        m = mi.depolarizer(f)
        s = dr.norm(dr.cross(mi.Vector3f(0, 0, 1), si.wi))
        sin_i = dr.safe_sqrt(dr.square(si.wi.x) + dr.square(si.wi.y))
        m[1][2] = f * (sin_i - s) / s            # DEFECT: 0/0 = NaN at normal incidence
        return m

    def eval(self, ctx, si, wo, active=True):
        return dr.select(self._ok(si, wo), self._value(ctx, si, wo), 0.0)

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
        return bs, dr.select(bs.pdf > 0, value, 0.0)

    def to_string(self):
        return "NanOffDiagonal[]"


mi.register_bsdf("defect_nan_offdiagonal", lambda props: NanOffDiagonal(props))
