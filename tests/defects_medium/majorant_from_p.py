"""The control with its majorant taken from the density at mei.p, floored at 1: the author
reads mei.p as the ray's start, but Mitsuba queries get_majorant before p is set
(src/render/medium.cpp:47-62: p = 0, where the blob is empty), so the majorant is 1, below
σ_t in the core, while σ_n = PEAK − σ_t: σ_t + σ_n ≠ majorant (topic majorant).
"""
import drjit as dr
import mitsuba as mi

PEAK = 4.0
TINT = (1.0, 0.7, 0.4)


def density(p):
    r2 = dr.squared_norm(p - mi.Point3f(0.5, 0.5, 0.5)) / (0.45 * 0.45)
    return PEAK * dr.square(dr.maximum(1.0 - r2, 0.0))


class MajorantFromP(mi.Medium):
    def __init__(self, props):
        mi.Medium.__init__(self, props)
        self.m_is_homogeneous = False
        self.m_has_spectral_extinction = True
        self.bbox = mi.BoundingBox3f(mi.Point3f(0.0, 0.0, 0.0), mi.Point3f(1.0, 1.0, 1.0))

    def intersect_aabb(self, ray):
        return self.bbox.ray_intersect(ray)

    def get_majorant(self, mei, active=True):
        return mi.UnpolarizedSpectrum(dr.maximum(density(mei.p), 1.0))

    def get_scattering_coefficients(self, mei, active=True):
        sigma_t = density(mei.p) * mi.UnpolarizedSpectrum(*TINT)
        return 0.8 * sigma_t, mi.UnpolarizedSpectrum(PEAK) - sigma_t, sigma_t

    def to_string(self):
        return "MajorantFromP[]"


mi.register_medium("defect_majorant_from_p", lambda props: MajorantFromP(props))
