"""Planted defect: a cut-out Lambertian whose eval_null_transmission() returns the opacity.

A diffuse surface of opacity o (0.3) with holes: sample() picks the diffuse lobe with
probability o and otherwise the Null lobe (wo = −wi, weight 1, pdf 1 − o), as Mitsuba's
``mask`` does (mask.cpp:128-141), and honours a context restricted to one lobe.  The light
that passes un-scattered is 1 − o, but eval_null_transmission() returns o: shadow rays in
volpath see the surface 0.3 transparent, paths through sample() 0.7.  eval, pdf, sample and
the default eval_diffuse_reflectance (π·eval(wi, n) = o·ρ) are right, so only the
``eval_null_transmission`` topic can see it.
"""

import drjit as dr
import mitsuba as mi

DIFFUSE, NULL = 0, 1


class NullWrong(mi.BSDF):
    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.reflectance = mi.Float(props.get("reflectance", 0.5))
        self.opacity = mi.Float(props.get("opacity", 0.3))
        self.m_components = [mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide,
                             mi.BSDFFlags.Null | mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide]
        self.m_flags = self.m_components[0] | self.m_components[1]

    def traverse(self, callback):
        callback.put("reflectance", self.reflectance, mi.ParamFlags.Differentiable)

    def _ok(self, si, wo):
        return (mi.Frame3f.cos_theta(si.wi) > 0) & (mi.Frame3f.cos_theta(wo) > 0)

    def _prob_diffuse(self, ctx):
        """Probability of the diffuse lobe given the lobes the context enables."""
        diffuse = ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, DIFFUSE)
        null = ctx.is_enabled(mi.BSDFFlags.Null, NULL)
        if diffuse and null:
            return self.opacity
        return mi.Float(1.0 if diffuse else 0.0)

    def eval(self, ctx, si, wo, active=True):
        if not ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, DIFFUSE):
            return mi.Spectrum(0.0)
        value = self.opacity * self.reflectance * dr.inv_pi * mi.Frame3f.cos_theta(wo)
        return dr.select(self._ok(si, wo), mi.Spectrum(value), 0.0)

    def pdf(self, ctx, si, wo, active=True):
        density = self._prob_diffuse(ctx) * mi.warp.square_to_cosine_hemisphere_pdf(wo)
        return dr.select(self._ok(si, wo), density, 0.0)

    def eval_pdf(self, ctx, si, wo, active=True):
        return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

    def sample(self, ctx, si, sample1, sample2, active=True):
        p = self._prob_diffuse(ctx)
        enabled = (ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, DIFFUSE)
                   or ctx.is_enabled(mi.BSDFFlags.Null, NULL))
        diffuse = sample1 < p
        bs = dr.zeros(mi.BSDFSample3f)
        wo_d = mi.warp.square_to_cosine_hemisphere(sample2)
        bs.wo = dr.select(diffuse, wo_d, -si.wi)
        bs.pdf = dr.select(diffuse, self.pdf(ctx, si, wo_d), 1.0 - p)
        bs.eta = 1.0
        bs.sampled_type = dr.select(diffuse, mi.UInt32(int(mi.BSDFFlags.DiffuseReflection)),
                                    mi.UInt32(int(mi.BSDFFlags.Null)))
        bs.sampled_component = dr.select(diffuse, mi.UInt32(DIFFUSE), mi.UInt32(NULL))
        f = self.eval(ctx, si, wo_d) / dr.select(bs.pdf > 0, bs.pdf, 1.0)
        # The Null lobe passes (1 − o) of the light: weight (1 − o) / pdf(Null) = (1 − o)/(1 − p)
        null = (1.0 - self.opacity) / dr.select(1.0 - p > 0, 1.0 - p, 1.0)
        value = dr.select(diffuse, f, mi.Spectrum(null))
        return bs, dr.select((bs.pdf > 0) & enabled, value, 0.0)

    def eval_null_transmission(self, si, active=True):
        return mi.Spectrum(self.opacity)                        # DEFECT: 1 − opacity passes

    def to_string(self):
        return "NullWrong[]"


mi.register_bsdf("defect_null_transmission_wrong", lambda props: NullWrong(props))
