"""A correct homogeneous medium written as a plugin author would (the second control).

Grey fog, σ_t = 1.5 everywhere (unbounded: intersect_aabb hits every ray on [0, ∞)), albedo
0.6, σ_n = 0 and majorant = σ_t, flagged homogeneous and grey, an hg phase function nested in
its properties when the caller gives one (isotropic otherwise).
"""
import drjit as dr
import mitsuba as mi


class FogControl(mi.Medium):
    def __init__(self, props):
        mi.Medium.__init__(self, props)
        self.sigma_t = props.get("sigma_t", 1.5)
        self.m_is_homogeneous = True
        self.m_has_spectral_extinction = False

    def intersect_aabb(self, ray):
        return mi.Bool(True), mi.Float(0.0), mi.Float(dr.inf)

    def get_majorant(self, mei, active=True):
        return mi.UnpolarizedSpectrum(self.sigma_t)

    def get_scattering_coefficients(self, mei, active=True):
        sigma_t = mi.UnpolarizedSpectrum(self.sigma_t)
        return 0.6 * sigma_t, mi.UnpolarizedSpectrum(0.0), sigma_t

    def to_string(self):
        return "FogControl[]"


mi.register_medium("defect_fog_control", lambda props: FogControl(props))
