r"""The ``gradient`` topic: Dr.Jit's derivative of ``eval`` against finite differences.

For each differentiable parameter x of ``mi.traverse(bsdf)`` (floats, colours, texture data;
others are skipped with the reason), the functional S(x) = Σ_lanes Σ_channels c_l eval(ω_i, ω_o)
over fixed random directions (ω_o on the whole sphere) and fixed weights c_l ∈ [0.5, 1.5]: the
derivative a differentiable renderer takes of a BSDF at an interaction.  The verdict -- the
direction v, forward-mode AD, the central (or, for a non-negative parameter with an element at
0, the second-order one-sided) differences at the fixed step 2⁻⁷ (a conductor's Fresnel term
at eta = 0 cancels in float32 at smaller steps), the lanes left out (a jump or kink that moves with x: roughdielectric's total-internal-reflection
boundary under eta, flagged ``ParamFlags.Discontinuous``), the tolerance
4|D(h) − D(h/2)| + 64u(Σ|eval|/h + Σ|∂eval|) -- is every kind's:
:func:`phonglab.validate.gradient.verdict`.  A delta lobe's eval is 0, so a BSDF whose lobes are
all deltas has nothing to compare.  Needs an AD variant (``llvm_ad_*``/``cuda_ad_*``); elsewhere
the topic is one skipped row.
"""

from __future__ import annotations

import mitsuba as mi
import numpy as np

from ...verdict import NOT_APPLICABLE
from ... import probe
from . import lanes
from ..gradient import AtFixedInputs, verdict, without_ad
from .topics import Row


def _directions(opts):
    r = lanes.rng(opts.seed, "gradient")
    n = opts.gradient_lanes
    wi = lanes.sphere(r, n)
    wi[:, 2] = np.abs(wi[:, 2]) + 0.05
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    return wi, lanes.sphere(r, n), 0.5 + r.random(n)


def gradient(bsdf, opts) -> list[Row]:
    skipped = without_ad(Row)
    if skipped:
        return skipped
    if lanes.delta_only(bsdf):
        return [Row("gradient", "AD derivatives", None, None, None, None, "skipped",
                    "every lobe is a delta: eval is 0 everywhere, so no parameter has a "
                    "derivative of eval to compare (a limit of the check, not a defect of the "
                    "BSDF)", {NOT_APPLICABLE: True})]
    params = mi.traverse(bsdf)
    keys = list(params.keys())
    if not keys:
        return [Row("gradient", "AD derivatives", None, None, None, None, "skipped",
                    "mi.traverse exposes no parameter", {NOT_APPLICABLE: True})]
    wi, wo, c = _directions(opts)
    plugin, ctx = probe.view(bsdf), probe.context()
    si, wo = probe.interaction(wi), probe.to_vectors(wo)
    fn = AtFixedInputs(lambda: plugin.eval(ctx, si, wo), c, "Σ c·eval", "eval", "BSDF",
                       max_halvings=0, kinks=False)
    rows = []
    for key in keys:
        flags = params.properties[key][3]
        if flags & int(mi.ParamFlags.NonDifferentiable):
            rows.append(Row("gradient", key, None, None, None, None, "skipped",
                            "flagged non-differentiable by the plugin (ParamFlags)",
                            {NOT_APPLICABLE: True}))
        else:
            rows.append(verdict(fn, params, key,
                                bool(flags & int(mi.ParamFlags.Discontinuous)), Row))
    return rows
