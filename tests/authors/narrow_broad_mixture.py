"""A plugin author's two-lobe BSDF, correct: a normalized Blinn-Phong lobe of exponent in the
thousands beside a Lambertian lobe.

    D(h)     = (p + 1)/(2π) cos^p θ_h                    (the density of h it samples)
    f_s      = k_s D(h) / (4 (ω_i·h) max(cos θ_i, cos θ_o))   (reciprocal, albedo ≤ k_s)
    f        = k_d/π + f_s
    pdf      = (1 − w_s) cos θ_o/π + w_s D(h)/(4 (ω_o·h)),   w_s = k_s/(k_d + k_s)

Each lobe is sampled by its own exact inverse CDF (cos θ_h = u^(1/(p+1)), φ = 2πu';
cosine-weighted hemisphere), the lobe chosen by u < w_s, and a reflected direction below the
horizon is rejected (weight 0).  So ∫pdf dω_o = (1 − w_s) + w_s·P_s(θ_i), P_s the fraction of
the Blinn-Phong lobe's reflections above the horizon: exactly the fraction counted.

``pdf_scale`` (default 1, not traversed, so never swept): a test knob that plants a pdf off
by that factor (pdf and bs.pdf scaled, weight = eval/bs.pdf, so only the normalization sees
it), as tests/defects/pdf_scaled_1pct.py does for a Lambert.

k_d + k_s ≤ 1 (a point above is refused at load, as phonglab's phong does).  The declared
ranges are [1e-4, 1], so that the sweep, --quick's ends included, reaches w_s ≈ 1e-4
(k_s = 1e-4 beside the default k_d) and w_s ≈ 1 − 1e-4, and a --set of k_d = 1 − w_s, k_s = w_s
(the tests' mixtures from 1e-4 to 1 − 1e-4) lies inside them; the exponents span 1e3 .. 1e4.
"""

import drjit as dr
import mitsuba as mi


class NarrowBroadMixture(mi.BSDF):
    PARAMETER_RANGES = {"diffuse_reflectance": (1e-4, 1.0),
                        "specular_reflectance": (1e-4, 1.0),
                        "exponent": (1e3, 1e4, (5e3,))}

    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        kd = float(props.get("diffuse_reflectance", 0.5))
        ks = float(props.get("specular_reflectance", 0.5))
        if kd + ks > 1.0 + 1e-6:
            raise ValueError(f"diffuse_reflectance + specular_reflectance = {kd + ks} > 1")
        self.kd, self.ks = mi.Float(kd), mi.Float(ks)
        self.exponent = mi.Float(props.get("exponent", 2000.0))
        self.pdf_scale = float(props.get("pdf_scale", 1.0))
        dr.make_opaque(self.kd, self.ks, self.exponent)
        diffuse = mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide
        glossy = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
        self.m_components = [diffuse, glossy]
        self.m_flags = diffuse | glossy

    def traverse(self, callback):
        callback.put("diffuse_reflectance", self.kd, mi.ParamFlags.Differentiable)
        callback.put("specular_reflectance", self.ks, mi.ParamFlags.Differentiable)
        callback.put("exponent", self.exponent, mi.ParamFlags.Differentiable)

    def _enabled(self, ctx):
        return (ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, 0),
                ctx.is_enabled(mi.BSDFFlags.GlossyReflection, 1))

    def _w_s(self, has_d, has_s):
        if not (has_d and has_s):
            return mi.Float(1.0 if has_s else 0.0)
        total = self.kd + self.ks
        return dr.select(total > 0, self.ks / dr.select(total > 0, total, 1.0), 0.0)

    def _ok(self, si, wo):
        return (mi.Frame3f.cos_theta(si.wi) > 0) & (mi.Frame3f.cos_theta(wo) > 0)

    def _half(self, si, wo):
        """(D(h), ω·h) for h = normalize(ω_i + ω_o), in forms that keep float32 precision:
        ω_i·h = ω_o·h = |ω_i + ω_o|/2 for unit vectors (dot(ω_o, h) cancels at grazing
        incidence), and cos^p θ_h = exp(p/2 · log(1 − sin²θ_h)) with sin²θ_h from h's tangent
        components and log(1 − t) by its series for small t (cos θ_h = h.z rounds to the
        float32 grid below 1, a relative error of p·2⁻²⁴ in cos^p, which near normal incidence
        does not average out: it integrated to 1 + 1.6e-4 at p = 10⁴)."""
        s = si.wi + wo
        n2 = dr.squared_norm(s)
        n = dr.sqrt(n2)
        t = (s.x * s.x + s.y * s.y) / dr.maximum(n2, 1e-30)        # sin²θ_h
        log_c2 = dr.select(t < 1e-3, -t * (1.0 + t * (0.5 + t * (1.0 / 3.0))),
                           dr.log(dr.maximum(1.0 - t, 1e-30)))      # log cos²θ_h
        d = (self.exponent + 1) * dr.inv_two_pi * dr.exp(0.5 * self.exponent * log_c2)
        return dr.select(s.z > 0, d, 0.0), 0.5 * n

    def _eval(self, ctx, si, wo):
        has_d, has_s = self._enabled(ctx)
        d, cos_h = self._half(si, wo)
        ci, co = mi.Frame3f.cos_theta(si.wi), mi.Frame3f.cos_theta(wo)
        f = mi.Float(0.0)
        if has_d:
            f += self.kd * dr.inv_pi
        if has_s:
            f += self.ks * d / (4 * dr.maximum(cos_h, 1e-30) * dr.maximum(ci, co))
        return dr.select(self._ok(si, wo), f * co, 0.0)

    def _pdf(self, ctx, si, wo):
        has_d, has_s = self._enabled(ctx)
        w_s = self._w_s(has_d, has_s)
        d, cos_h = self._half(si, wo)
        p = (1 - w_s) * mi.warp.square_to_cosine_hemisphere_pdf(wo)
        p += w_s * d / (4 * dr.maximum(cos_h, 1e-30))
        return dr.select(self._ok(si, wo), self.pdf_scale * p, 0.0)

    def eval(self, ctx, si, wo, active=True):
        return mi.Spectrum(self._eval(ctx, si, wo))

    def pdf(self, ctx, si, wo, active=True):
        return self._pdf(ctx, si, wo)

    def eval_pdf(self, ctx, si, wo, active=True):
        return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

    def sample(self, ctx, si, sample1, sample2, active=True):
        has_d, has_s = self._enabled(ctx)
        bs = dr.zeros(mi.BSDFSample3f)
        if not (has_d or has_s):
            return bs, mi.Spectrum(0.0)
        pick_s = sample1 < self._w_s(has_d, has_s)
        # cos θ_h = u^(1/(p+1)); 1 − cos θ_h = −expm1(ln u/(p+1)) keeps sin θ_h precise
        x = dr.log(sample2.x) / (self.exponent + 1)
        one_minus = dr.select(x > -1e-3, -x * (1.0 + x * (0.5 + x * (1.0 / 6.0))),
                              1.0 - dr.exp(x))
        cos_h = 1.0 - one_minus
        sin_h = dr.safe_sqrt(one_minus * (2.0 - one_minus))
        s, c = dr.sincos(dr.two_pi * sample2.y)
        h = mi.Vector3f(sin_h * c, sin_h * s, cos_h)
        wo_s = 2 * dr.dot(si.wi, h) * h - si.wi
        wo_d = mi.warp.square_to_cosine_hemisphere(sample2)
        bs.wo = dr.select(pick_s, wo_s, wo_d)
        bs.eta = 1.0
        bs.sampled_component = dr.select(pick_s, mi.UInt32(1), mi.UInt32(0))
        bs.sampled_type = dr.select(pick_s, mi.UInt32(+mi.BSDFFlags.GlossyReflection),
                                    mi.UInt32(+mi.BSDFFlags.DiffuseReflection))
        bs.pdf = self._pdf(ctx, si, bs.wo)
        ok = self._ok(si, bs.wo) & (bs.pdf > 0)
        weight = self._eval(ctx, si, bs.wo) / dr.select(ok, bs.pdf, 1.0)
        return bs, mi.Spectrum(dr.select(ok, weight, 0.0))

    def to_string(self):
        return "NarrowBroadMixture[]"


mi.register_bsdf("narrow_broad_mixture", lambda props: NarrowBroadMixture(props))
