"""unimplemented_pdf -- a Lambertian BSDF whose author only needed BSDF sampling
(e.g. for a pure path-sampling integrator) and left ``pdf``/``eval_pdf`` as stubs, as
some published research code does.

Style: research code; ``active`` positional WITHOUT a default; reflectance a
``mi.Color3f`` from ``props.get('reflectance', 0.5)`` (float or rgb); ``m_flags`` and
``m_components`` set; neither ``traverse`` nor ``to_string``.

BUG (one): ``pdf`` and ``eval_pdf`` raise ``NotImplementedError``.  ``eval`` (rho/pi
cos) and ``sample`` (cosine-weighted, weight rho) are correct.  Physical property
broken: none of the values -- the BSDF cannot be used by anything that asks for its
density (Mitsuba's ``path`` integrator calls ``eval_pdf`` for next-event estimation
and for MIS, so the render fails).

OBSERVED (3.9.1): ``mi.render`` with ``path`` raises ``RuntimeError: drjit.custom(
<mitsuba.python.util._RenderOp>): error while performing a custom differentiable
operation`` whose ``__cause__`` is this ``NotImplementedError``.  ``direct`` with
``emitter_samples=0`` never asks for the BSDF density and renders exactly like
``diffuse`` (ratio 1.0000).  Beware: while ANY instance of this BSDF is alive (even one
that is in no scene), every later ``path`` render in the same process fails the same
way, because Dr.Jit's symbolic virtual calls trace every live BSDF instance.
"""

import drjit as dr
import mitsuba as mi


class UnimplementedPdf(mi.BSDF):
    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.reflectance = mi.Color3f(props.get('reflectance', 0.5))
        self.m_components = [mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide]
        self.m_flags = self.m_components[0]

    def sample(self, ctx, si, sample1, sample2, active):
        bs = dr.zeros(mi.BSDFSample3f)
        if not ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, 0):
            return bs, mi.Color3f(0.0)
        active = active & (mi.Frame3f.cos_theta(si.wi) > 0.0)
        bs.wo = mi.warp.square_to_cosine_hemisphere(sample2)
        bs.pdf = mi.warp.square_to_cosine_hemisphere_pdf(bs.wo)
        bs.eta = 1.0
        bs.sampled_type = mi.UInt32(+mi.BSDFFlags.DiffuseReflection)
        bs.sampled_component = mi.UInt32(0)
        active = active & (bs.pdf > 0.0)
        return bs, dr.select(active, self.reflectance, 0.0)

    def eval(self, ctx, si, wo, active):
        if not ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, 0):
            return mi.Color3f(0.0)
        cos_theta_i = mi.Frame3f.cos_theta(si.wi)
        cos_theta_o = mi.Frame3f.cos_theta(wo)
        active = active & (cos_theta_i > 0.0) & (cos_theta_o > 0.0)
        return dr.select(active, self.reflectance * dr.inv_pi * cos_theta_o, 0.0)

    def pdf(self, ctx, si, wo, active):
        raise NotImplementedError('UnimplementedPdf.pdf')

    def eval_pdf(self, ctx, si, wo, active):
        raise NotImplementedError('UnimplementedPdf.eval_pdf')


mi.register_bsdf('unimplemented_pdf', lambda props: UnimplementedPdf(props))
