"""tut_isotropic -- an isotropic phase function in the style of the Mitsuba 3
tutorials/trampoline tests.

Style: tutorial; ``active`` positional WITHOUT a default; ``self.m_flags =
mi.PhaseFunctionFlags.Isotropic``; returns what Mitsuba 3.9.1's PhaseFunction
interface expects: ``sample`` -> ``(wo, weight, pdf)`` (weight a Spectrum, here the
Python float 1.0) and ``eval_pdf`` -> ``(value, pdf)``.  (3.9.1 has no separate
``eval``/``pdf`` methods on PhaseFunction: checked with ``dir(mi.PhaseFunction)`` and
``help(mi.PhaseFunction.sample)`` / ``help(mi.PhaseFunction.eval_pdf)``.)  No
``traverse``; ``to_string`` present.

CONTROL (correct): p(wo) = 1/(4 pi), uniform sphere sampling, weight 1.
"""

import drjit as dr
import mitsuba as mi


class TutIsotropic(mi.PhaseFunction):
    def __init__(self, props):
        mi.PhaseFunction.__init__(self, props)
        self.m_flags = mi.PhaseFunctionFlags.Isotropic

    def sample(self, ctx, mei, sample1, sample2, active):
        wo = mi.warp.square_to_uniform_sphere(sample2)
        pdf = mi.warp.square_to_uniform_sphere_pdf(wo)
        return wo, 1.0, pdf

    def eval_pdf(self, ctx, mei, wo, active):
        value = mi.warp.square_to_uniform_sphere_pdf(wo)
        return value, value

    def to_string(self):
        return 'TutIsotropic[]'


mi.register_phase('tut_isotropic', lambda props: TutIsotropic(props))
