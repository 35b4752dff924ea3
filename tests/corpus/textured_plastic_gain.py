"""textured_plastic_gain -- a textured "plastic" (Lambertian base + normalized Phong
gloss lobe) of the kind found in research/teaching code.

Style: every parameter is read with ``props.get_texture`` (``diffuse_reflectance``
0.5, ``specular_reflectance`` 0.2, ``roughness`` 0.5) and evaluated per hit with
``tex.eval(si, active)`` / ``tex.eval_1(si, active)``, so each accepts a float, an
rgb or a ``<texture type="bitmap"/"uniform">``; ``active`` positional WITHOUT a
default; flags through ``self.m_flags`` / ``self.m_components``; ``traverse`` and
``to_string`` present; NO ``PARAMETER_RANGES``.

The gloss lobe is the modified Phong lobe around the mirror direction,
f_s = k_s * C * cos^m(alpha), with the exponent derived from the roughness texture,
n = 2/roughness^2 - 2.  To keep ``cos^m`` away from float32 underflow the lobe
exponent is clamped, m = min(n, 164).

BUG (one): the normalization uses the UNCLAMPED exponent, C = (n + 2)/(2 pi), instead
of the lobe's own (m + 2)/(2 pi).  For roughness >= ~0.11 (n <= 164, including the
default 0.5) nothing changes and the BSDF is energy conserving; below that the lobe is
too bright by (n + 2)/(m + 2), e.g. 200/166 = 1.20 at roughness 0.1.  Physical property
broken: energy conservation (hemispherical albedo > 1), visible only when the roughness
is swept.  Sampling draws the clamped lobe and ``pdf`` is its exact density, and the
sample weight is eval/pdf, so sampling and pdf agree (chi2 passes); only eval's scale
is wrong.

Measured albedo (specular_reflectance 1, diffuse_reflectance 0; midpoint quadrature of
``mi.BSDF.eval(plugin, ctx, si, wo, True)`` over the hemisphere, 2048 x 512 (theta, phi)
cells; a 200k-sample Monte Carlo mean of the ``sample`` weights agrees to 1e-3):
  roughness 0.05: 4.819 (0 deg)  4.174 (30 deg)  2.410 (60 deg)
  roughness 0.1 : 1.2048 (0 deg) 1.0434 (30 deg) 0.6024 (60 deg)
  roughness 0.2 : 1.0000 (0 deg) 0.8660 (30 deg) 0.5000 (60 deg)
  roughness 0.5 : 1.0000 (0 deg) 0.8661 (30 deg) 0.5142 (60 deg)
The pdf integrates to 1.000 (0.915 at 60 deg, roughness 0.5: lobe mass below the
horizon, which ``sample`` returns with weight 0).
White furnace (sphere, specular 1, diffuse 0, constant env 1, ``path`` max_depth 16,
32x32, 16 spp, centre 16x16 pixels): roughness 0.5 -> 0.899, 0.2 -> 0.898,
0.1 -> 1.083 (> 1: the gain shows in a render too).
"""

import drjit as dr
import mitsuba as mi

MAX_EXPONENT = 164.0


def _mean(c):
    return (c[0] + c[1] + c[2]) * (1.0 / 3.0)


class TexturedPlasticGain(mi.BSDF):
    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.diffuse_reflectance = props.get_texture('diffuse_reflectance', 0.5)
        self.specular_reflectance = props.get_texture('specular_reflectance', 0.2)
        self.roughness = props.get_texture('roughness', 0.5)

        self.m_components = [
            mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide,
            mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide,
        ]
        self.m_flags = self.m_components[0] | self.m_components[1]

    # -- helpers -----------------------------------------------------------------
    def _lobes(self, ctx, si, active):
        kd = self.diffuse_reflectance.eval(si, active)
        ks = self.specular_reflectance.eval(si, active)
        r = dr.maximum(self.roughness.eval_1(si, active), 1e-3)
        n = 2.0 / dr.square(r) - 2.0
        n = dr.maximum(n, 0.0)
        m = dr.minimum(n, MAX_EXPONENT)
        norm = (n + 2.0) * (0.5 * dr.inv_pi)

        has_d = ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, 0)
        has_s = ctx.is_enabled(mi.BSDFFlags.GlossyReflection, 1)
        if has_d and has_s:
            wd, ws = _mean(kd), _mean(ks)
            total = wd + ws
            p_spec = dr.select(total > 0.0, ws / dr.select(total > 0.0, total, 1.0), 0.5)
        elif has_s:
            p_spec = mi.Float(1.0)
        else:
            p_spec = mi.Float(0.0)
        return kd, ks, m, norm, p_spec, has_d, has_s

    def _eval_pdf(self, ctx, si, wo, active):
        kd, ks, m, norm, p_spec, has_d, has_s = self._lobes(ctx, si, active)
        cos_theta_i = mi.Frame3f.cos_theta(si.wi)
        cos_theta_o = mi.Frame3f.cos_theta(wo)
        active = active & (cos_theta_i > 0.0) & (cos_theta_o > 0.0)

        cos_alpha = dr.dot(mi.reflect(si.wi), wo)
        lobe = dr.select(cos_alpha > 0.0, dr.power(dr.maximum(cos_alpha, 0.0), m), 0.0)

        value = mi.Color3f(0.0)
        if has_d:
            value += kd * dr.inv_pi
        if has_s:
            value += ks * norm * lobe
        value = value * cos_theta_o

        pdf_d = cos_theta_o * dr.inv_pi
        pdf_s = (m + 1.0) * (0.5 * dr.inv_pi) * lobe
        pdf = (1.0 - p_spec) * pdf_d + p_spec * pdf_s

        return dr.select(active, value, 0.0), dr.select(active, pdf, 0.0)

    # -- BSDF interface ------------------------------------------------------------
    def sample(self, ctx, si, sample1, sample2, active):
        kd, ks, m, norm, p_spec, has_d, has_s = self._lobes(ctx, si, active)
        bs = dr.zeros(mi.BSDFSample3f)
        if not (has_d or has_s):
            return bs, mi.Color3f(0.0)

        cos_theta_i = mi.Frame3f.cos_theta(si.wi)
        active = active & (cos_theta_i > 0.0)

        pick_s = sample1 < p_spec

        # Phong lobe around the mirror direction
        cos_alpha = dr.power(sample2.x, 1.0 / (m + 1.0))
        sin_alpha = dr.safe_sqrt(1.0 - dr.square(cos_alpha))
        s, c = dr.sincos(2.0 * dr.pi * sample2.y)
        local = mi.Vector3f(sin_alpha * c, sin_alpha * s, cos_alpha)
        wo_s = mi.Frame3f(mi.reflect(si.wi)).to_world(local)

        wo_d = mi.warp.square_to_cosine_hemisphere(sample2)

        bs.wo = dr.select(pick_s, wo_s, wo_d)
        bs.eta = 1.0
        bs.sampled_component = dr.select(pick_s, mi.UInt32(1), mi.UInt32(0))
        bs.sampled_type = dr.select(pick_s, mi.UInt32(+mi.BSDFFlags.GlossyReflection),
                                    mi.UInt32(+mi.BSDFFlags.DiffuseReflection))

        value, pdf = self._eval_pdf(ctx, si, bs.wo, active)
        bs.pdf = pdf
        active = active & (pdf > 0.0)
        return bs, dr.select(active, value / dr.select(active, pdf, 1.0), 0.0)

    def eval(self, ctx, si, wo, active):
        return self._eval_pdf(ctx, si, wo, active)[0]

    def pdf(self, ctx, si, wo, active):
        return self._eval_pdf(ctx, si, wo, active)[1]

    def eval_pdf(self, ctx, si, wo, active):
        return self._eval_pdf(ctx, si, wo, active)

    def traverse(self, callback):
        callback.put('diffuse_reflectance', self.diffuse_reflectance,
                     mi.ParamFlags.Differentiable)
        callback.put('specular_reflectance', self.specular_reflectance,
                     mi.ParamFlags.Differentiable)
        callback.put('roughness', self.roughness, mi.ParamFlags.Differentiable)

    def to_string(self):
        return ('TexturedPlasticGain[\n'
                f'  diffuse_reflectance = {self.diffuse_reflectance},\n'
                f'  specular_reflectance = {self.specular_reflectance},\n'
                f'  roughness = {self.roughness}\n]')


mi.register_bsdf('textured_plastic_gain', lambda props: TexturedPlasticGain(props))
