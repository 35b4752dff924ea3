"""The control whose σ_s carries twice its derivative in ``albedo`` (topic gradient): the
value albedo·σ_t, written as (2·albedo − detach(albedo))·σ_t, the kind of slip a hand-written
derivative or a stray dr.detach leaves behind; what it renders is unchanged.

σ_t(p) = 4 (1 − |p − c|²/R²)² (0.5, 0.35, 0.2)/0.5 inside the ball of radius R = 0.45 about
c = (0.5, 0.5, 0.5), 0 outside; its bounds the unit cube [0, 1]³ (mi.BoundingBox3f); the
majorant its peak in every channel, and σ_n = majorant − σ_t (Mitsuba's null-collision
coefficient, src/media/heterogeneous.cpp:194); albedo 0.8, traversed as a differentiable
``albedo`` (an opaque mi.Float); spectral extinction flagged.
"""
import drjit as dr
import mitsuba as mi

PEAK = 4.0
TINT = (1.0, 0.7, 0.4)


def density(p):
    r2 = dr.squared_norm(p - mi.Point3f(0.5, 0.5, 0.5)) / (0.45 * 0.45)
    return PEAK * dr.square(dr.maximum(1.0 - r2, 0.0))


class WrongGradient(mi.Medium):
    def __init__(self, props):
        mi.Medium.__init__(self, props)
        self.m_is_homogeneous = False
        self.m_has_spectral_extinction = True
        self.bbox = mi.BoundingBox3f(mi.Point3f(0.0, 0.0, 0.0), mi.Point3f(1.0, 1.0, 1.0))
        self.albedo = dr.opaque(mi.Float, 0.8)

    def traverse(self, callback):
        callback.put("albedo", self.albedo, mi.ParamFlags.Differentiable)

    def parameters_changed(self, keys=[]):
        pass

    def intersect_aabb(self, ray):
        return self.bbox.ray_intersect(ray)

    def get_majorant(self, mei, active=True):
        return mi.UnpolarizedSpectrum(PEAK)

    def get_scattering_coefficients(self, mei, active=True):
        sigma_t = density(mei.p) * mi.UnpolarizedSpectrum(*TINT)
        return (2.0 * self.albedo - dr.detach(self.albedo)) * sigma_t, mi.UnpolarizedSpectrum(PEAK) - sigma_t, sigma_t

    def to_string(self):
        return "WrongGradient[]"


mi.register_medium("defect_wrong_gradient", lambda props: WrongGradient(props))
