r"""Modified Phong BSDF (``phong``): energy-normalized, reciprocal, written in Python/Dr.Jit.

.. list-table::

   * - diffuse_reflectance
     - |spectrum| or |texture|
     - k_d in [0, 1] (default 0.5). Exposed, differentiable.
   * - specular_reflectance
     - |spectrum| or |texture|
     - k_s in [0, 1] (default 0.2); k_d + k_s <= 1 in every channel. Exposed, differentiable.
   * - exponent
     - |float|
     - The shininess p >= 0 of the seed's cos^p term (default 30). Exposed, differentiable;
       held as an opaque ``mi.Float`` so that changing it never recompiles the kernel.

Math, as the code computes it (radiance units, local shading frame, ω_i = si.wi)::

    R(ω_i)  = 2 (N·ω_i) N − ω_i                  the seed's mirror direction, = mi.reflect(ω_i)
    cos α   = max(0, ω_o · R(ω_i))
    f_r     = k_d / π + k_s (p+2)/(2π) cos^p α   [Lafortune & Willems 1994]
    eval    = f_r cos θ_o
    pdf     = (1 − w_s) cos θ_o / π + w_s (p+1)/(2π) cos^p α
    w_s     = mean(k_s) / (mean(k_d) + mean(k_s))  (lobe selection weight at si)
    weight  = eval / pdf                          (from the mixture, never from one lobe)

The (p+2)/(2π) factor makes the specular lobe's directional albedo exactly k_s
at normal incidence (∫ cos^p α cos θ_o dω_o = 2π/(p+2) when R = N); at oblique
incidence part of the lobe falls below the horizon and the albedo drops below
k_d + k_s, so the model never creates energy when k_d + k_s <= 1.  f_r is
reciprocal because ω_o·R(ω_i) = ω_i·R(ω_o).  p = 0 gives a uniform lobe
(k_s/π over the hemisphere around R); the seed's classic term k_spec (L·R)^p is
this lobe without the normalization and without the cosine.

Specular sampling draws the lobe around R (``square_to_phong_lobe``):
cos α = u^(1/(p+1)), φ = 2π u'.  For huge exponents 1 − cos α is computed from
expm1(ln u / (p+1)) so that sin α keeps its precision in float32 (p = 10^5 is
fine).  Samples that land below the horizon carry weight 0.

References: B. T. Phong, "Illumination for computer generated pictures",
CACM 18(6), 1975; E. P. Lafortune, Y. D. Willems, "Using the modified Phong
reflectance model for physically based rendering", KU Leuven CW197, 1994.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi

from . import _common

DIFFUSE = 0  #: component index of the diffuse lobe
GLOSSY = 1   #: component index of the specular (glossy) lobe


def _one_minus_exp(t):
    """1 − exp(t) for t <= 0, accurate also when |t| is tiny (a float32 expm1)."""
    series = -t * (1.0 + t * (0.5 + t * (1.0 / 6.0)))
    return dr.select(t > -1e-3, series, 1.0 - dr.exp(t))


def square_to_phong_lobe(sample, exponent):
    """Warp a uniform square sample to the cos^p lobe around +Z.

    cos α = u^(1/(p+1)), φ = 2π u'; density (p+1)/(2π) cos^p α per steradian.
    """
    t = dr.log(sample.x) / (exponent + 1.0)
    one_minus_cos = _one_minus_exp(t)
    cos_alpha = 1.0 - one_minus_cos
    sin_alpha = dr.safe_sqrt(one_minus_cos * (2.0 - one_minus_cos))
    sin_phi, cos_phi = dr.sincos(dr.two_pi * sample.y)
    return mi.Vector3f(sin_alpha * cos_phi, sin_alpha * sin_phi, cos_alpha)


def square_to_phong_lobe_pdf(v, exponent):
    """Density of :func:`square_to_phong_lobe` at the unit vector v (around +Z)."""
    return (exponent + 1.0) * dr.inv_two_pi * phong_lobe(v.z, exponent)


def phong_lobe(cos_alpha, exponent):
    """max(0, cos α)^p, with 0^0 := 0 below the axis' hemisphere and cos α clamped to 1."""
    positive = cos_alpha > 0
    c = dr.minimum(dr.select(positive, cos_alpha, 1.0), 1.0)
    return dr.select(positive, dr.power(c, exponent), 0.0)


class Phong(mi.BSDF):
    """f = k_d/π + k_s (p+2)/(2π) cos^p α, sampled as a mixture of its two lobes."""

    #: The valid range of each parameter (lo, hi[, edges]) for ``phonglab validate``'s sweep:
    #: p from a uniform lobe to a near-mirror one, with small exponents, where the (p+1)
    #: and (p+2) normalizations differ most, as edges.
    PARAMETER_RANGES = {"diffuse_reflectance": (0.0, 1.0), "specular_reflectance": (0.0, 1.0),
                        "exponent": (0.0, 1e4, (1.0, 5.0))}

    def __init__(self, props: mi.Properties):
        mi.BSDF.__init__(self, props)
        self.diffuse_reflectance, self.specular_reflectance = _common.load_textures(
            "phong", props, [("diffuse_reflectance", 0.5), ("specular_reflectance", 0.2)],
            energy=True)
        exponent = _common.check_exponent("phong", props.get("exponent", 30.0))
        self.exponent = mi.Float(exponent)
        diffuse = mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide
        glossy = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
        self.m_components = [diffuse, glossy]   # indices DIFFUSE, GLOSSY
        self.m_flags = diffuse | glossy
        self._update_factors()
        self._accepted = _common.snapshot(self._members())

    def traverse(self, callback):
        callback.put("diffuse_reflectance", self.diffuse_reflectance, mi.ParamFlags.Differentiable)
        callback.put("specular_reflectance", self.specular_reflectance, mi.ParamFlags.Differentiable)
        callback.put("exponent", self.exponent, mi.ParamFlags.Differentiable)

    def _members(self) -> dict:
        """The traversed members, whose values an update writes in place."""
        return {"diffuse_reflectance": self.diffuse_reflectance,
                "specular_reflectance": self.specular_reflectance, "exponent": self.exponent}

    def parameters_changed(self, keys=None):
        """Re-validate after ``params.update()`` (an optimizer step, a sweep), then re-derive.

        Transactional: a refused value is replaced by the last accepted one (in the BSDF
        and in the caller's parameter map) before the :class:`MaterialError` propagates.
        """
        keys = keys or []

        def validate():
            if any("reflectance" in k for k in keys) and not mi.is_spectral:
                # In spectral variants textures hold up-sampled spectra: see _common.declared_value.
                _common.check_textures("phong", {
                    "diffuse_reflectance": self.diffuse_reflectance,
                    "specular_reflectance": self.specular_reflectance}, energy=True)
            _common.check_exponent("phong", _common.scalar_of(self.exponent))

        self._accepted = _common.commit(self._members(), self._accepted, validate,
                                        self._update_factors)

    def _update_factors(self):
        # An opaque exponent is a kernel input, not a baked literal: sweeps never recompile.
        dr.make_opaque(self.exponent)
        self.brdf_factor = (self.exponent + 2.0) * dr.inv_two_pi   # normalizes f_r's lobe
        self.pdf_factor = (self.exponent + 1.0) * dr.inv_two_pi    # normalizes the sampling lobe
        # Evaluated too, so that a freshly loaded BSDF and an updated one trace the same
        # kernel (otherwise the first exponent update compiled one more kernel).
        dr.make_opaque(self.brdf_factor, self.pdf_factor)

    def _lobes(self, ctx, si, active):
        """Enabled lobes, their reflectances and the specular selection weight at si."""
        has_diffuse = ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, DIFFUSE)
        has_glossy = ctx.is_enabled(mi.BSDFFlags.GlossyReflection, GLOSSY)
        kd = self.diffuse_reflectance.eval(si, active)
        ks = self.specular_reflectance.eval(si, active)
        if has_diffuse and has_glossy:
            md, ms = dr.mean(kd), dr.mean(ks)
            total = md + ms
            w_s = dr.select(total > 0, ms / dr.select(total > 0, total, 1.0), 0.0)
        else:
            w_s = mi.Float(1.0 if has_glossy else 0.0)
        return has_diffuse, has_glossy, kd, ks, w_s

    def eval(self, ctx, si, wo, active=True):
        return self.eval_pdf(ctx, si, wo, active)[0]

    def pdf(self, ctx, si, wo, active=True):
        return self.eval_pdf(ctx, si, wo, active)[1]

    def eval_pdf(self, ctx, si, wo, active=True):
        return self._eval_pdf(si, wo, active, self._lobes(ctx, si, active))

    def _eval_pdf(self, si, wo, active, lobes):
        """eval and pdf of the mixture at wo, from the lobes :meth:`_lobes` found at si."""
        has_diffuse, has_glossy, kd, ks, w_s = lobes
        cos_theta_i = mi.Frame3f.cos_theta(si.wi)
        cos_theta_o = mi.Frame3f.cos_theta(wo)
        active &= (cos_theta_i > 0) & (cos_theta_o > 0) & (has_diffuse or has_glossy)
        value = dr.zeros(mi.UnpolarizedSpectrum)
        pdf = mi.Float(0.0)
        if has_diffuse:
            value += kd * dr.inv_pi
            pdf += (1.0 - w_s) * cos_theta_o * dr.inv_pi
        if has_glossy:
            lobe = phong_lobe(dr.dot(wo, mi.reflect(si.wi)), self.exponent)
            value += ks * (self.brdf_factor * lobe)
            pdf += w_s * self.pdf_factor * lobe
        # Polarized variants: a diffuse/glossy scatterer is an ideal depolarizer (as in diffuse.cpp).
        value = mi.depolarizer(value * cos_theta_o) if mi.is_polarized else value * cos_theta_o
        return dr.select(active, value, 0.0), dr.select(active, pdf, 0.0)

    def sample(self, ctx, si, sample1, sample2, active=True):
        lobes = self._lobes(ctx, si, active)
        has_diffuse, has_glossy, _, _, w_s = lobes
        bs = dr.zeros(mi.BSDFSample3f)
        active &= mi.Frame3f.cos_theta(si.wi) > 0
        if not (has_diffuse or has_glossy):
            return bs, dr.zeros(mi.Spectrum)
        # Pick the lobe by weight: sample1 < w_s selects the specular lobe.
        glossy = (sample1 < w_s) if (has_diffuse and has_glossy) else has_glossy
        wo_diffuse = mi.warp.square_to_cosine_hemisphere(sample2)
        # Lobe around the mirror direction: cos α = u^(1/(p+1)), φ = 2πu' [Lafortune & Willems 1994]
        wo_glossy = mi.Frame3f(mi.reflect(si.wi)).to_world(square_to_phong_lobe(sample2, self.exponent))
        bs.wo = dr.select(glossy, wo_glossy, wo_diffuse)
        bs.eta = 1.0
        bs.sampled_component = dr.select(glossy, mi.UInt32(GLOSSY), mi.UInt32(DIFFUSE))
        bs.sampled_type = dr.select(glossy, mi.UInt32(int(mi.BSDFFlags.GlossyReflection)),
                                    mi.UInt32(int(mi.BSDFFlags.DiffuseReflection)))
        # The weight comes from the whole mixture, so sample, eval and pdf never disagree
        # (the textures at si are evaluated once, for the lobe choice and the mixture).
        value, bs.pdf = self._eval_pdf(si, bs.wo, active, lobes)
        active &= bs.pdf > 0
        return bs, dr.select(active, value / dr.select(active, bs.pdf, 1.0), 0.0)

    def eval_diffuse_reflectance(self, si, active=True):
        return self.diffuse_reflectance.eval(si, active)

    def to_string(self):
        return (f"Phong[\n  diffuse_reflectance = {self.diffuse_reflectance},\n"
                f"  specular_reflectance = {self.specular_reflectance},\n"
                f"  exponent = {_common.scalar_of(self.exponent)}\n]")


PLUGIN_CLASS = Phong
