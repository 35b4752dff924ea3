"""Planted defect (gradient): HG whose value is right and whose derivative in g is twice the
true one: it evaluates at g_eff = 2g − detach(g), which equals g but moves twice as fast under
AD (a gradient written by hand and doubled).  Sampling, pdf and weight are HG's."""
import runpy
from pathlib import Path

import drjit as dr
import mitsuba as mi

c = runpy.run_path(str(Path(__file__).with_name("hg_control.py")), run_name="_hg")


class HGWrongGradient(c["HGControl"]):
    def eval_pdf(self, ctx, mei, wo, active=True):
        g = 2.0 * self.g - dr.detach(self.g)
        p = c["hg"](g, -dr.dot(wo, mei.wi))
        return mi.Spectrum(p), dr.detach(p)


mi.register_phase("defect_hg_wrong_gradient", lambda props: HGWrongGradient(props))
