"""two_lobe_control -- a diffuse + perfect-mirror two-lobe BSDF ("coated" / "plastic
without Fresnel") of the kind written in research code.

Style: two components in ``self.m_components`` (0: DiffuseReflection, 1:
DeltaReflection), ``self.m_flags`` their union; ``diffuse_reflectance`` (0.5) and
``specular_reflectance`` (0.3) read with ``props.get_texture``; ``active`` positional
WITHOUT a default; ``to_string`` but no ``traverse``.

f(wi, wo) = k_d/pi + k_s * delta(wo - reflect(wi)).  The lobe to sample is chosen
with probability proportional to the mean of each reflectance; the delta sample's
``bs.pdf`` is its discrete probability, as in Mitsuba's built-in ``plastic``.

CONTROL (correct): honours both ``ctx.type_mask`` and ``ctx.component`` through
``ctx.is_enabled(flag, component)`` in sample, eval and pdf.
"""

import drjit as dr
import mitsuba as mi


def _mean(c):
    return (c[0] + c[1] + c[2]) * (1.0 / 3.0)


class TwoLobeControl(mi.BSDF):
    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.diffuse_reflectance = props.get_texture('diffuse_reflectance', 0.5)
        self.specular_reflectance = props.get_texture('specular_reflectance', 0.3)

        diffuse = mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide
        mirror = mi.BSDFFlags.DeltaReflection | mi.BSDFFlags.FrontSide
        self.m_components = [diffuse, mirror]
        self.m_flags = diffuse | mirror

    def _enabled(self, ctx):
        # (diffuse lobe requested, mirror lobe requested)
        return (ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, 0),
                ctx.is_enabled(mi.BSDFFlags.DeltaReflection, 1))

    def _prob_mirror(self, has_d, has_s, kd, ks):
        if has_d and has_s:
            total = _mean(kd) + _mean(ks)
            return dr.select(total > 0.0, _mean(ks) / dr.select(total > 0.0, total, 1.0), 0.0)
        return mi.Float(1.0 if has_s else 0.0)

    def sample(self, ctx, si, sample1, sample2, active):
        has_d, has_s = self._enabled(ctx)
        bs = dr.zeros(mi.BSDFSample3f)
        if not (has_d or has_s):
            return bs, mi.Color3f(0.0)

        cos_theta_i = mi.Frame3f.cos_theta(si.wi)
        active = active & (cos_theta_i > 0.0)

        kd = self.diffuse_reflectance.eval(si, active)
        ks = self.specular_reflectance.eval(si, active)
        p_s = self._prob_mirror(has_d, has_s, kd, ks)

        pick_s = sample1 < p_s
        wo_d = mi.warp.square_to_cosine_hemisphere(sample2)

        bs.wo = dr.select(pick_s, mi.reflect(si.wi), wo_d)
        bs.eta = 1.0
        bs.sampled_component = dr.select(pick_s, mi.UInt32(1), mi.UInt32(0))
        bs.sampled_type = dr.select(pick_s, mi.UInt32(+mi.BSDFFlags.DeltaReflection),
                                    mi.UInt32(+mi.BSDFFlags.DiffuseReflection))
        bs.pdf = dr.select(pick_s, p_s,
                           (1.0 - p_s) * mi.warp.square_to_cosine_hemisphere_pdf(wo_d))

        weight = dr.select(pick_s, ks / dr.select(p_s > 0.0, p_s, 1.0),
                           kd / dr.select(p_s < 1.0, 1.0 - p_s, 1.0))
        active = active & (bs.pdf > 0.0)
        return bs, dr.select(active, weight, 0.0)

    def eval(self, ctx, si, wo, active):
        has_d, has_s = self._enabled(ctx)
        if not has_d:
            return mi.Color3f(0.0)
        cos_theta_i = mi.Frame3f.cos_theta(si.wi)
        cos_theta_o = mi.Frame3f.cos_theta(wo)
        active = active & (cos_theta_i > 0.0) & (cos_theta_o > 0.0)
        value = self.diffuse_reflectance.eval(si, active) * dr.inv_pi * cos_theta_o
        return dr.select(active, value, 0.0)

    def pdf(self, ctx, si, wo, active):
        has_d, has_s = self._enabled(ctx)
        if not has_d:
            return mi.Float(0.0)
        cos_theta_i = mi.Frame3f.cos_theta(si.wi)
        cos_theta_o = mi.Frame3f.cos_theta(wo)
        active = active & (cos_theta_i > 0.0) & (cos_theta_o > 0.0)
        kd = self.diffuse_reflectance.eval(si, active)
        ks = self.specular_reflectance.eval(si, active)
        p_s = self._prob_mirror(has_d, has_s, kd, ks)
        pdf = (1.0 - p_s) * mi.warp.square_to_cosine_hemisphere_pdf(wo)
        return dr.select(active, pdf, 0.0)

    def eval_pdf(self, ctx, si, wo, active):
        return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

    def to_string(self):
        return (f'TwoLobeControl[diffuse_reflectance={self.diffuse_reflectance}, '
                f'specular_reflectance={self.specular_reflectance}]')


mi.register_bsdf('two_lobe_control', lambda props: TwoLobeControl(props))
