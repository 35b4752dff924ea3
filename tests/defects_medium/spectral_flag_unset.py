"""The control without m_has_spectral_extinction (its σ_t differs between channels): volpath
takes the grey path, weighting a real collision σ_s/σ_t and drawing distances with one
channel's majorant (topic flags).
"""
import drjit as dr
import mitsuba as mi

PEAK = 4.0
TINT = (1.0, 0.7, 0.4)


def density(p):
    r2 = dr.squared_norm(p - mi.Point3f(0.5, 0.5, 0.5)) / (0.45 * 0.45)
    return PEAK * dr.square(dr.maximum(1.0 - r2, 0.0))


class SpectralFlagUnset(mi.Medium):
    def __init__(self, props):
        mi.Medium.__init__(self, props)
        self.m_is_homogeneous = False
        self.m_has_spectral_extinction = False
        self.bbox = mi.BoundingBox3f(mi.Point3f(0.0, 0.0, 0.0), mi.Point3f(1.0, 1.0, 1.0))

    def intersect_aabb(self, ray):
        return self.bbox.ray_intersect(ray)

    def get_majorant(self, mei, active=True):
        return mi.UnpolarizedSpectrum(PEAK)

    def get_scattering_coefficients(self, mei, active=True):
        sigma_t = density(mei.p) * mi.UnpolarizedSpectrum(*TINT)
        return 0.8 * sigma_t, mi.UnpolarizedSpectrum(PEAK) - sigma_t, sigma_t

    def to_string(self):
        return "SpectralFlagUnset[]"


mi.register_medium("defect_spectral_flag_unset", lambda props: SpectralFlagUnset(props))
