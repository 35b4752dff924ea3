r"""Lambertian BSDF (``lambert``): the ideal diffuse reflector, written in Python/Dr.Jit.

.. list-table::

   * - reflectance
     - |spectrum| or |texture|
     - Diffuse reflectance ρ in [0, 1] (default 0.5). Exposed, differentiable.

The same parameter as Mitsuba's built-in ``diffuse``, so that a comparison swaps
only the ``type``.  One-sided like ``diffuse`` (wrap it in ``twosided`` for a
two-sided surface).

Math, as the code computes it (radiance units, local shading frame)::

    f_r(ω_i, ω_o) = ρ / π                       (Lambert's law: radiance independent of ω_o)
    eval          = f_r cos θ_o                 (Mitsuba's eval carries the cosine)
    pdf           = cos θ_o / π                 (cosine-weighted hemisphere, Malley's method)
    sample weight = eval / pdf = ρ              (exactly: zero variance under constant light)

Both directions must lie above the surface (cos θ_i > 0, cos θ_o > 0); elsewhere
eval, pdf and the sample weight are 0.  The directional albedo is
∫ f_r cos θ_o dω_o = ρ for every incidence, the white-furnace check.

References: J. H. Lambert, *Photometria* (1760); M. Pharr, W. Jakob, G. Humphreys,
*Physically Based Rendering*, 4th ed., §9.2 (DiffuseBxDF) and §A.5.3.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi

from . import _common

DIFFUSE = 0  #: component index of the diffuse lobe


class Lambert(mi.BSDF):
    """f = ρ/π, cosine-weighted importance sampling."""

    #: The valid range of each parameter (lo, hi[, edges]) for ``phonglab validate``'s sweep.
    PARAMETER_RANGES = {"reflectance": (0.0, 1.0)}

    def __init__(self, props: mi.Properties):
        mi.BSDF.__init__(self, props)
        (self.reflectance,) = _common.load_textures("lambert", props, [("reflectance", 0.5)])
        flags = mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide
        self.m_components = [flags]
        self.m_flags = flags
        self._accepted = _common.snapshot(self._members())

    def traverse(self, callback):
        callback.put("reflectance", self.reflectance, mi.ParamFlags.Differentiable)

    def _members(self) -> dict:
        return {"reflectance": self.reflectance}

    def parameters_changed(self, keys=None):
        """Re-validate the reflectance after ``params.update()``; a refused value is
        replaced by the last accepted one before the error propagates (not checked in
        spectral variants, whose textures hold up-sampled spectra: see
        ``_common.declared_value``)."""
        def validate():
            if keys and not mi.is_spectral:
                _common.check_textures("lambert", self._members())

        self._accepted = _common.commit(self._members(), self._accepted, validate, lambda: None)

    def _active(self, ctx, si, wo, active):
        enabled = ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, DIFFUSE)
        cos_theta_i = mi.Frame3f.cos_theta(si.wi)
        cos_theta_o = mi.Frame3f.cos_theta(wo)
        return active & enabled & (cos_theta_i > 0) & (cos_theta_o > 0), cos_theta_o

    def _value(self, si, scale, active):
        value = self.reflectance.eval(si, active) * scale
        # Polarized variants: a diffuse scatterer is an ideal depolarizer (as in diffuse.cpp).
        return mi.depolarizer(value) if mi.is_polarized else value

    def eval(self, ctx, si, wo, active=True):
        active, cos_theta_o = self._active(ctx, si, wo, active)
        return dr.select(active, self._value(si, dr.inv_pi * cos_theta_o, active), 0.0)

    def pdf(self, ctx, si, wo, active=True):
        active, cos_theta_o = self._active(ctx, si, wo, active)
        return dr.select(active, cos_theta_o * dr.inv_pi, 0.0)

    def eval_pdf(self, ctx, si, wo, active=True):
        active, cos_theta_o = self._active(ctx, si, wo, active)
        value = self._value(si, dr.inv_pi * cos_theta_o, active)
        return dr.select(active, value, 0.0), dr.select(active, cos_theta_o * dr.inv_pi, 0.0)

    def sample(self, ctx, si, sample1, sample2, active=True):
        cos_theta_i = mi.Frame3f.cos_theta(si.wi)
        active &= (cos_theta_i > 0) & ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, DIFFUSE)
        bs = dr.zeros(mi.BSDFSample3f)
        # Malley's method: uniform on the unit disk, projected up to the hemisphere.
        bs.wo = mi.warp.square_to_cosine_hemisphere(sample2)
        bs.pdf = mi.warp.square_to_cosine_hemisphere_pdf(bs.wo)
        bs.eta = 1.0
        bs.sampled_type = mi.UInt32(int(mi.BSDFFlags.DiffuseReflection))
        bs.sampled_component = mi.UInt32(DIFFUSE)
        active &= bs.pdf > 0
        # eval / pdf = (ρ/π cos θ_o) / (cos θ_o/π) = ρ: the cosines cancel exactly.
        return bs, dr.select(active, self._value(si, 1.0, active), 0.0)

    def eval_diffuse_reflectance(self, si, active=True):
        return self.reflectance.eval(si, active)

    def to_string(self):
        return f"Lambert[\n  reflectance = {self.reflectance}\n]"


PLUGIN_CLASS = Lambert
