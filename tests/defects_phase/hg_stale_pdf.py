"""Planted defect (pdf): sample() reports 1.25 × the density it draws from (a stale
normalization left in the sampling routine); eval_pdf, the directions and the weight
(value/pdf of eval_pdf = 1) are HG's, so an integrator's MIS weight is what goes wrong."""
import runpy
from pathlib import Path

import mitsuba as mi

c = runpy.run_path(str(Path(__file__).with_name("hg_control.py")), run_name="_hg")


class HGStalePdf(c["HGControl"]):
    def sample(self, ctx, mei, sample1, sample2, active=True):
        wo, w, pdf = super().sample(ctx, mei, sample1, sample2, active)
        return wo, w, 1.25 * pdf


mi.register_phase("defect_hg_stale_pdf", lambda props: HGStalePdf(props))
