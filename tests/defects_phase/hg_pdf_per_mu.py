"""Planted defect (normalization): value and pdf are densities per unit of mu = cos θ, not per
steradian (2π too large: the azimuth's measure forgotten), consistently in sample and eval_pdf,
weight = value/pdf = 1: the shape is right, only the integral over the sphere (2π) is not.
"""
import runpy
from pathlib import Path

import drjit as dr
import mitsuba as mi

c = runpy.run_path(str(Path(__file__).with_name("hg_control.py")), run_name="_hg")


class HGPerMu(c["HGControl"]):
    def sample(self, ctx, mei, sample1, sample2, active=True):
        mu = c["sample_mu"](self.g, sample2.x)
        return (c["direction"](mei, mu, sample2.y), mi.Spectrum(1.0),
                2.0 * dr.pi * c["hg"](self.g, mu))

    def eval_pdf(self, ctx, mei, wo, active=True):
        p = 2.0 * dr.pi * c["hg"](self.g, -dr.dot(wo, mei.wi))
        return mi.Spectrum(p), p


mi.register_phase("defect_hg_pdf_per_mu", lambda props: HGPerMu(props))
