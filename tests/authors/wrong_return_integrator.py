"""Planted defect: an integrator whose ``sample()`` returns a bare Spectrum instead of the
tuple (Spectrum, Bool valid, list of AOVs) Mitsuba expects.  Before phonglab checked the
returned types on a one-lane call, Mitsuba aborted the process inside Dr.Jit (exit 134,
"unknown variable"), with no report."""

import drjit as dr
import mitsuba as mi


class WrongReturn(mi.SamplingIntegrator):
    def __init__(self, props):
        mi.SamplingIntegrator.__init__(self, props)

    def sample(self, scene, sampler, ray, medium=None, active=True):
        si = scene.ray_intersect(ray, active)
        return si.emitter(scene).eval(si, active)             # DEFECT: not (L, valid, aovs)


mi.register_integrator("defect_wrong_return", lambda props: WrongReturn(props))
