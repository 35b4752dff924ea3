"""Planted defect (weight): the sample weight is 2·u1 instead of value/pdf = 1: right on average
(E[2 u1] = 1), wrong per sample; directions and pdf are HG's."""
import runpy
from pathlib import Path

import mitsuba as mi

c = runpy.run_path(str(Path(__file__).with_name("hg_control.py")), run_name="_hg")


class HGWeightNoise(c["HGControl"]):
    def sample(self, ctx, mei, sample1, sample2, active=True):
        wo, _, pdf = super().sample(ctx, mei, sample1, sample2, active)
        return wo, mi.Spectrum(2.0 * sample1), pdf


mi.register_phase("defect_hg_weight_noise", lambda props: HGWeightNoise(props))
