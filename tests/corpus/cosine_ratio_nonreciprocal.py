"""cosine_ratio_nonreciprocal -- a diffuse BSDF with a misplaced "shading-normal
correction", as found in research code that ports a path tracer's adjoint fix-up into
the BSDF itself.

Style: research code; ``reflectance`` read with ``props.get_texture('reflectance', 0.5)``;
``active`` positional WITHOUT a default; ``m_flags``/``m_components`` set;
``traverse`` present, no ``to_string``.

BUG (one): eval multiplies the Lambertian term by the ratio cos(theta_i)/cos(theta_o)
(the Veach shading-normal correction factor, applied unconditionally and in the wrong
place), so eval = rho/pi * cos(theta_o) * cos(theta_i)/cos(theta_o) = rho/pi * cos(theta_i).
The BSDF f = rho/pi * cos(theta_i)/cos(theta_o) is no longer symmetric:
f(wi, wo) != f(wo, wi).  Physical property broken: reciprocity.  pdf and sample are
consistent with this eval (eval is constant in wo, so wo is drawn uniformly over the
hemisphere, pdf 1/(2 pi), weight 2 rho cos(theta_i)): chi2 passes.
Side effect to know: the albedo is 2 rho cos(theta_i), so energy is conserved only for
rho <= 0.5 (the default 0.5 reaches exactly 1 at normal incidence); a reflectance sweep
above 0.5 also shows an energy gain.

OBSERVED: wi = (0.2, 0, 0.95), wo = (-0.8, 0, 0.3) (normalized), rho 0.5:
f(wi, wo) = 0.4436, f(wo, wi) = 0.0571.  ``path`` render (sphere + floor, 32x32,
16 spp): 0.2517 vs built-in ``diffuse`` 0.2699 (a different BSDF, for scale only).
"""

import drjit as dr
import mitsuba as mi


class CosineRatioNonreciprocal(mi.BSDF):
    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.reflectance = props.get_texture('reflectance', 0.5)
        self.m_components = [mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide]
        self.m_flags = self.m_components[0]

    def eval(self, ctx, si, wo, active):
        if not ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, 0):
            return mi.Color3f(0.0)
        cos_theta_i = mi.Frame3f.cos_theta(si.wi)
        cos_theta_o = mi.Frame3f.cos_theta(wo)
        active = active & (cos_theta_i > 0.0) & (cos_theta_o > 0.0)

        f = self.reflectance.eval(si, active) * dr.inv_pi
        # "shading normal correction"
        correction = cos_theta_i / dr.select(active, cos_theta_o, 1.0)
        return dr.select(active, f * correction * cos_theta_o, 0.0)

    def pdf(self, ctx, si, wo, active):
        if not ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, 0):
            return mi.Float(0.0)
        cos_theta_i = mi.Frame3f.cos_theta(si.wi)
        cos_theta_o = mi.Frame3f.cos_theta(wo)
        active = active & (cos_theta_i > 0.0) & (cos_theta_o > 0.0)
        return dr.select(active, mi.warp.square_to_uniform_hemisphere_pdf(wo), 0.0)

    def eval_pdf(self, ctx, si, wo, active):
        return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

    def sample(self, ctx, si, sample1, sample2, active):
        bs = dr.zeros(mi.BSDFSample3f)
        if not ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, 0):
            return bs, mi.Color3f(0.0)
        bs.wo = mi.warp.square_to_uniform_hemisphere(sample2)
        bs.eta = 1.0
        bs.sampled_type = mi.UInt32(+mi.BSDFFlags.DiffuseReflection)
        bs.sampled_component = mi.UInt32(0)
        value, bs.pdf = self.eval_pdf(ctx, si, bs.wo, active)
        active = active & (bs.pdf > 0.0)
        return bs, dr.select(active, value / dr.select(active, bs.pdf, 1.0), 0.0)

    def traverse(self, callback):
        callback.put('reflectance', self.reflectance, mi.ParamFlags.Differentiable)


mi.register_bsdf('cosine_ratio_nonreciprocal', lambda props: CosineRatioNonreciprocal(props))
