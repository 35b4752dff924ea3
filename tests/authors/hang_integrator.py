"""Planted defect: an integrator whose ``sample()`` never returns (a Python ``while True`` on
its first call).  ``--timeout`` turns each topic that renders with it into a failing row."""

import mitsuba as mi


class HangSample(mi.SamplingIntegrator):
    def __init__(self, props):
        mi.SamplingIntegrator.__init__(self, props)

    def sample(self, scene, sampler, ray, medium=None, active=True):
        while True:                                           # DEFECT: never returns
            pass


mi.register_integrator("defect_hang_sample", lambda props: HangSample(props))
