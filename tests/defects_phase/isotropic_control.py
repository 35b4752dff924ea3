"""A correct isotropic phase function (the control): uniform on the sphere, value = pdf = 1/4π."""
import mitsuba as mi


class IsotropicControl(mi.PhaseFunction):
    def __init__(self, props):
        mi.PhaseFunction.__init__(self, props)
        self.m_flags = mi.PhaseFunctionFlags.Isotropic

    def sample(self, ctx, mei, sample1, sample2, active=True):
        wo = mi.warp.square_to_uniform_sphere(sample2)
        return wo, mi.Spectrum(1.0), mi.warp.square_to_uniform_sphere_pdf(wo)

    def eval_pdf(self, ctx, mei, wo, active=True):
        p = mi.warp.square_to_uniform_sphere_pdf(wo)
        return mi.Spectrum(p), p


mi.register_phase("defect_isotropic_control", lambda props: IsotropicControl(props))
