"""A correct Henyey-Greenstein phase function written as a plugin author would (the control).

Mitsuba's convention (src/phase/hg.cpp:97): mi.wi points back along the incoming light, the
scattering angle's cosine is mu = -dot(wo, wi), g > 0 peaks at wo = -wi.  p(mu) =
(1 - g²) / (4π (1 + g² - 2 g mu)^1.5) per steradian; sample() inverts its CDF in mu.
"""
import drjit as dr
import mitsuba as mi


def hg(g, mu):
    temp = 1.0 + g * g - 2.0 * g * mu
    return (1.0 - g * g) / (4.0 * dr.pi * temp * dr.sqrt(temp))


def sample_mu(g, u):
    """The inverse CDF of HG in mu (|g| > 1e-3 here: every plugin of this folder uses g = ±0.5
    unless it says otherwise)."""
    s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u)
    return dr.clip((1.0 + g * g - s * s) / (2.0 * g), -1.0, 1.0)


def direction(mei, mu, u):
    """wo at scattering cosine mu about the forward direction -wi, azimuth 2π u."""
    sin_t = dr.safe_sqrt(1.0 - mu * mu)
    s, c = dr.sincos(2.0 * dr.pi * u)
    return mi.Frame3f(-mei.wi).to_world(mi.Vector3f(sin_t * c, sin_t * s, mu))


class HGControl(mi.PhaseFunction):
    def __init__(self, props):
        mi.PhaseFunction.__init__(self, props)
        self.g = mi.Float(props.get("g", 0.5))
        self.m_flags = mi.PhaseFunctionFlags.Anisotropic

    def traverse(self, cb):
        cb.put("g", self.g, mi.ParamFlags.Differentiable)

    def parameters_changed(self, keys=[]):
        pass

    def sample(self, ctx, mei, sample1, sample2, active=True):
        mu = sample_mu(self.g, sample2.x)
        wo = direction(mei, mu, sample2.y)
        return wo, mi.Spectrum(1.0), hg(self.g, mu)

    def eval_pdf(self, ctx, mei, wo, active=True):
        p = hg(self.g, -dr.dot(wo, mei.wi))
        return mi.Spectrum(p), p

    def to_string(self):
        return "HGControl[]"


mi.register_phase("defect_hg_control", lambda props: HGControl(props))
