"""Planted defect: eval_null_transmission() returns 1 for a BSDF without a Null lobe.

A Lambertian (flags: DiffuseReflection only) that reports full un-scattered transmission, as
if copied from a cut-out or a null interface: volpath would let shadow rays pass through it
(volpath.cpp:531) while sample() never passes light straight through.  eval, pdf and sample
are right, so only the ``eval_null_transmission`` topic can see it.
"""

import drjit as dr
import mitsuba as mi


class NullWithoutLobe(mi.BSDF):
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
        bs.pdf = self.pdf(ctx, si, bs.wo)
        bs.eta = 1.0
        bs.sampled_type = mi.UInt32(int(mi.BSDFFlags.DiffuseReflection))
        bs.sampled_component = mi.UInt32(0)
        value = self.eval(ctx, si, bs.wo) / dr.select(bs.pdf > 0, bs.pdf, 1.0)
        return bs, dr.select(bs.pdf > 0, value, 0.0)

    def eval_null_transmission(self, si, active=True):
        return mi.Spectrum(1.0)                                          # DEFECT: no Null lobe

    def to_string(self):
        return "NullWithoutLobe[]"


mi.register_bsdf("defect_null_transmission_without_lobe", lambda props: NullWithoutLobe(props))
