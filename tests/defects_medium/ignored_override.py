"""The control with its own sample_interaction, drawing the free-flight distance against the
density at the ray's origin: Mitsuba's integrators never call it (the method is not
virtual, include/mitsuba/render/medium.h:53); they run the base class's (topic overrides).
"""
import drjit as dr
import mitsuba as mi

PEAK = 4.0
TINT = (1.0, 0.7, 0.4)


def density(p):
    r2 = dr.squared_norm(p - mi.Point3f(0.5, 0.5, 0.5)) / (0.45 * 0.45)
    return PEAK * dr.square(dr.maximum(1.0 - r2, 0.0))


class IgnoredOverride(mi.Medium):
    def __init__(self, props):
        mi.Medium.__init__(self, props)
        self.m_is_homogeneous = False
        self.m_has_spectral_extinction = True
        self.bbox = mi.BoundingBox3f(mi.Point3f(0.0, 0.0, 0.0), mi.Point3f(1.0, 1.0, 1.0))

    def intersect_aabb(self, ray):
        return self.bbox.ray_intersect(ray)

    def get_majorant(self, mei, active=True):
        return mi.UnpolarizedSpectrum(PEAK)

    def get_scattering_coefficients(self, mei, active=True):
        sigma_t = density(mei.p) * mi.UnpolarizedSpectrum(*TINT)
        return 0.8 * sigma_t, mi.UnpolarizedSpectrum(PEAK) - sigma_t, sigma_t

    def sample_interaction(self, ray, sample, channel, active):
        mei = mi.Medium.sample_interaction(self, ray, sample, channel, active)
        sigma = dr.maximum(density(ray.o), 0.5)
        t = mei.mint - dr.log(1.0 - sample) / sigma
        mei.t = dr.select(mei.is_valid(), t, dr.inf)
        mei.p = ray(t)
        return mei

    def to_string(self):
        return "IgnoredOverride[]"


mi.register_medium("defect_ignored_override", lambda props: IgnoredOverride(props))
