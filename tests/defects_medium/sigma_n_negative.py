"""The control with the majorant half its peak and σ_n = majorant − σ_t: the sum is right,
but σ_n < 0 in the core, a negative null-collision probability (topic majorant).
"""
import drjit as dr
import mitsuba as mi

PEAK = 4.0
TINT = (1.0, 0.7, 0.4)


def density(p):
    r2 = dr.squared_norm(p - mi.Point3f(0.5, 0.5, 0.5)) / (0.45 * 0.45)
    return PEAK * dr.square(dr.maximum(1.0 - r2, 0.0))


class SigmaNNegative(mi.Medium):
    def __init__(self, props):
        mi.Medium.__init__(self, props)
        self.m_is_homogeneous = False
        self.m_has_spectral_extinction = True
        self.bbox = mi.BoundingBox3f(mi.Point3f(0.0, 0.0, 0.0), mi.Point3f(1.0, 1.0, 1.0))

    def intersect_aabb(self, ray):
        return self.bbox.ray_intersect(ray)

    def get_majorant(self, mei, active=True):
        return mi.UnpolarizedSpectrum(0.5 * PEAK)

    def get_scattering_coefficients(self, mei, active=True):
        sigma_t = density(mei.p) * mi.UnpolarizedSpectrum(*TINT)
        return 0.8 * sigma_t, mi.UnpolarizedSpectrum(0.5 * PEAK) - sigma_t, sigma_t

    def to_string(self):
        return "SigmaNNegative[]"


mi.register_medium("defect_sigma_n_negative", lambda props: SigmaNNegative(props))
