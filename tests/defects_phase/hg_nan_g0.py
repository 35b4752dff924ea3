"""Planted defect (finite): HG sampled by the textbook inversion (1 + g² − s²)/(2g) with no
isotropic branch: at g = 0 (this plugin's default) s = 1 and cos θ = 0/0 = NaN in every sample.

g is an opaque Dr.Jit value (dr.make_opaque), as a differentiable parameter is: a literal 0
would let Dr.Jit fold 2·g and the 0/0 away at trace time, and the planted NaN would never fire.
eval_pdf is HG's (finite at g = 0).
"""
import runpy
from pathlib import Path

import drjit as dr
import mitsuba as mi

c = runpy.run_path(str(Path(__file__).with_name("hg_control.py")), run_name="_hg")


class HGNaN(c["HGControl"]):
    def __init__(self, props):
        super().__init__(props)
        self.g = mi.Float(props.get("g", 0.0))
        dr.make_opaque(self.g)

    def sample(self, ctx, mei, sample1, sample2, active=True):
        g = self.g
        s = (1.0 - g * g) / (1.0 - g + 2.0 * g * sample2.x)
        mu = (1.0 + g * g - s * s) / (2.0 * g)
        return c["direction"](mei, mu, sample2.y), mi.Spectrum(1.0), c["hg"](g, mu)


mi.register_phase("defect_hg_nan_g0", lambda props: HGNaN(props))
