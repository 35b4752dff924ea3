r"""The ``gradient`` topic: Dr.Jit's derivative of the sampled radiance / intensity against a
central finite difference, for every differentiable parameter ``mi.traverse`` exposes
(radiance, intensity, irradiance, an envmap's data, a spot's cutoff_angle and beam_width).

AD side: the derivative of S(x) = Σ_lanes c_l Σ_channels weight_l, the weights of
``sample_direction`` from the reference points (:func:`~.setup.ref_groups`) with fixed sample
values and c_l ∈ [0.5, 1.5] fixed -- the derivative an AD integrator uses for emitter
sampling.  FD side: the same sum with the samples held where they are at x, ds₀ (direction,
point, pdf), and with them the sampling factor w₀/e₀ (the weight over the arriving radiance
e₀ = eval_direction(ds₀) at x): Σ c_l w₀ eval_direction(ds₀)/e₀.  Mitsuba differentiates the
radiance and detaches the sampling (envmap.cpp rebuilds its warp from the data in
parameters_changed; the sampled direction and its pdf carry no derivative), so a difference
quotient of the weights themselves would move the samples and the pdf with x and measure
another quantity (envmap ``data``: 168 of 512 lanes jump).  For emitters whose sampling does not
depend on x (point, spot, area, constant) the two sides are the same function.  Holding
w₀/e₀ keeps the topic apart from ``weight``: a weight wrong by a factor (that topic's defect)
still has the derivative of that factor times the radiance's.

The step, its halving, the lanes left out (jumps, kinks, no arriving radiance) and the
tolerance are the shared verdict's: :func:`phonglab.validate.gradient.verdict`.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

from ...verdict import NOT_APPLICABLE
from ..gradient import verdict
from .config import rng
from .lanes import with_edges
from .setup import Setup, interaction, point2, ref_groups
from .topics import Row


def gradient(setup: Setup, opts) -> list[Row]:
    if not dr.is_diff_v(mi.Float):
        return [Row("gradient", "AD derivatives", None, None, None, None, "skipped",
                    f"{mi.variant()} has no automatic differentiation: use an llvm_ad_* variant",
                    {NOT_APPLICABLE: True})]
    params = mi.traverse(setup.emitter)
    # ReadOnly: traversed for reading, refused on update (sunsky's sun_direction when it is
    # computed from a date and place, sunsky.cpp:291)
    skip = int(mi.ParamFlags.NonDifferentiable) | int(mi.ParamFlags.ReadOnly)
    keys = [k for k in params.keys() if not params.properties[k][3] & skip]
    if not keys:
        return [Row("gradient", "AD derivatives", None, None, None, None, "skipped",
                    "mi.traverse exposes no differentiable parameter", {NOT_APPLICABLE: True})]
    n = max(1, opts.gradient_lanes // 4)
    groups = ref_groups(setup, n, opts.seed)
    p = np.concatenate([g.p for g in groups])
    r = rng(opts.seed, "gradient")
    it = interaction(p)
    u = point2(with_edges(r.random((len(p), 2)), n))
    c = 0.5 + r.random(len(p))
    return [verdict(setup, params, key, it, u, c, "emitter") for key in keys]
