"""Planted defect (chi2): a tabulated phase function whose sampling table differs from its
pdf table.  eval_pdf: piecewise-linear density in mu = cos θ from TABLE; sample(): mu drawn
from SAMPLING_TABLE (the same table with two entries swapped, as a stale copy would be), the
reported pdf eval_pdf's at the drawn direction, weight = value/pdf = 1.
"""
import drjit as dr
import mitsuba as mi

TABLE = [0.2, 0.5, 1.0, 2.0, 4.0]
SAMPLING_TABLE = [0.2, 0.5, 2.0, 1.0, 4.0]


class TabMismatch(mi.PhaseFunction):
    def __init__(self, props):
        mi.PhaseFunction.__init__(self, props)
        self.m_flags = mi.PhaseFunctionFlags.Anisotropic
        self.pdf_table = mi.ContinuousDistribution(mi.ScalarVector2f(-1.0, 1.0), mi.Float(TABLE))
        self.sampling = mi.ContinuousDistribution(mi.ScalarVector2f(-1.0, 1.0),
                                                  mi.Float(SAMPLING_TABLE))

    def _pdf(self, mu):
        return self.pdf_table.eval_pdf_normalized(mu) / (2.0 * dr.pi)

    def sample(self, ctx, mei, sample1, sample2, active=True):
        mu = self.sampling.sample(sample2.x)
        sin_t = dr.safe_sqrt(1.0 - mu * mu)
        s, c = dr.sincos(2.0 * dr.pi * sample2.y)
        wo = mi.Frame3f(-mei.wi).to_world(mi.Vector3f(sin_t * c, sin_t * s, mu))
        return wo, mi.Spectrum(1.0), self._pdf(-dr.dot(wo, mei.wi))

    def eval_pdf(self, ctx, mei, wo, active=True):
        p = self._pdf(-dr.dot(wo, mei.wi))
        return mi.Spectrum(p), p


mi.register_phase("defect_tab_mismatch", lambda props: TabMismatch(props))
