r"""The ``gradient`` topic: Dr.Jit's derivative of eval_pdf's value against a central finite
difference, for every differentiable parameter ``mi.traverse`` exposes (hg's g, tabphase's
values, sggx's S, blendphase's weight and its children's parameters).

S(x) = Σ_lanes c_l Σ_channels value_l(x), the value of eval_pdf at fixed (wi, wo) lanes (wi
uniform, wo half uniform and half within 0.1 of forward scattering, where a peaked lobe
changes most with g) and c_l ∈ [0.5, 1.5] fixed: the derivative a differentiable volumetric
path tracer uses for a phase-sampled or light-sampled direction (``sample``'s weight of an
exactly sampled phase function is the constant 1, hg.cpp line 89, and carries none).  The
verdict is every kind's (:func:`phonglab.validate.gradient.verdict`): forward-mode AD along v
(v_i = |x_i|), FD steps from 2⁻⁷ halved until the sums agree, lanes with a jump or kink left
out, tolerance 4|D(h) − D(h/2)| + 64u(Σ|S|/h + Σ|∂S|).
"""

from __future__ import annotations

import mitsuba as mi
import numpy as np

from ...verdict import NOT_APPLICABLE
from ... import probe
from ..gradient import AtFixedInputs, differentiable_keys, verdict, without_ad
from . import lanes
from .config import rng
from .topics import Row


def gradient(phase, opts) -> list[Row]:
    skipped = without_ad(Row)
    if skipped:
        return skipped
    params = mi.traverse(phase)
    keys = differentiable_keys(params)
    if not keys:
        return [Row("gradient", "AD derivatives", None, None, None, None, "skipped",
                    "mi.traverse exposes no differentiable parameter", {NOT_APPLICABLE: True})]
    r = rng(opts.seed, "gradient")
    n = opts.gradient_lanes
    wi = lanes.sphere(r, n)
    wo = lanes.sphere(r, n)[::-1].copy()
    d = -wi[: n // 2] + 0.1 * lanes.sphere(r, n // 2)
    wo[: n // 2] = d / np.linalg.norm(d, axis=1)[:, None]
    plugin, ctx = lanes.view(phase), lanes.context()
    it, wo, c = lanes.interaction(wi), probe.to_vectors(wo), 0.5 + r.random(n)
    fn = AtFixedInputs(lambda: plugin.eval_pdf(ctx, it, wo)[0], c, "Σ c·(eval_pdf value)",
                       "eval_pdf's value", "phase function")
    return [verdict(fn, params, key, row=Row) for key in keys]
