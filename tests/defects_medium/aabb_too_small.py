"""The control with bounds [0.2, 0.8]³ where the blob fills the ball of radius 0.45 about
(0.5, 0.5, 0.5): sample_interaction never samples the outer shell (topic bounds).
"""
import drjit as dr
import mitsuba as mi

PEAK = 4.0
TINT = (1.0, 0.7, 0.4)


def density(p):
    r2 = dr.squared_norm(p - mi.Point3f(0.5, 0.5, 0.5)) / (0.45 * 0.45)
    return PEAK * dr.square(dr.maximum(1.0 - r2, 0.0))


class AabbTooSmall(mi.Medium):
    def __init__(self, props):
        mi.Medium.__init__(self, props)
        self.m_is_homogeneous = False
        self.m_has_spectral_extinction = True
        self.bbox = mi.BoundingBox3f(mi.Point3f(0.2, 0.2, 0.2), mi.Point3f(0.8, 0.8, 0.8))

    def intersect_aabb(self, ray):
        return self.bbox.ray_intersect(ray)

    def get_majorant(self, mei, active=True):
        return mi.UnpolarizedSpectrum(PEAK)

    def get_scattering_coefficients(self, mei, active=True):
        sigma_t = density(mei.p) * mi.UnpolarizedSpectrum(*TINT)
        return 0.8 * sigma_t, mi.UnpolarizedSpectrum(PEAK) - sigma_t, sigma_t

    def to_string(self):
        return "AabbTooSmall[]"


mi.register_medium("defect_aabb_too_small", lambda props: AabbTooSmall(props))
