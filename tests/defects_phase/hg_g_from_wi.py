"""Planted defect (reciprocity): the asymmetry depends on the incident direction,
g = 0.5 wi.z, so p(wi, wo) uses g(wi) and p(wo, wi) g(wo).  For each wi it is an exact,
normalized, correctly sampled HG: only the exchange of wi and wo sees it.
"""
import runpy
from pathlib import Path

import drjit as dr
import mitsuba as mi

c = runpy.run_path(str(Path(__file__).with_name("hg_control.py")), run_name="_hg")


class HGFromWi(c["HGControl"]):
    def _g(self, mei):
        return 0.5 * mei.wi.z + 0.0 * self.g

    def sample(self, ctx, mei, sample1, sample2, active=True):
        g = self._g(mei)
        g = dr.select(dr.abs(g) < 1e-3, 1e-3, g)
        mu = c["sample_mu"](g, sample2.x)
        return c["direction"](mei, mu, sample2.y), mi.Spectrum(1.0), c["hg"](g, mu)

    def eval_pdf(self, ctx, mei, wo, active=True):
        g = self._g(mei)
        g = dr.select(dr.abs(g) < 1e-3, 1e-3, g)
        p = c["hg"](g, -dr.dot(wo, mei.wi))
        return mi.Spectrum(p), p


mi.register_phase("defect_hg_g_from_wi", lambda props: HGFromWi(props))
