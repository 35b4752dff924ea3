"""Planted defect (chi2): sample() draws with +g, eval_pdf evaluates -g.

The sample reports eval_pdf's pdf at the direction it drew and weight = value/pdf = 1, so
the identities hold and the density integrates to 1: only the distribution of the drawn
directions is wrong (a sign slip between the physics and the graphics convention).
"""
import runpy
from pathlib import Path

import drjit as dr
import mitsuba as mi

c = runpy.run_path(str(Path(__file__).with_name("hg_control.py")), run_name="_hg")


class HGOppositeG(c["HGControl"]):
    def sample(self, ctx, mei, sample1, sample2, active=True):
        wo = c["direction"](mei, c["sample_mu"](self.g, sample2.x), sample2.y)
        return wo, mi.Spectrum(1.0), c["hg"](-self.g, -dr.dot(wo, mei.wi))

    def eval_pdf(self, ctx, mei, wo, active=True):
        p = c["hg"](-self.g, -dr.dot(wo, mei.wi))
        return mi.Spectrum(p), p


mi.register_phase("defect_hg_opposite_g", lambda props: HGOppositeG(props))
