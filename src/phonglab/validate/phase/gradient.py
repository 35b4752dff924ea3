r"""The ``gradient`` topic: Dr.Jit's derivative of eval_pdf's value against a central finite
difference, for every differentiable parameter ``mi.traverse`` exposes (hg's g, tabphase's
values, sggx's S, blendphase's weight and its children's parameters).

S(x) = Σ_lanes c_l Σ_channels value_l(x), the value of eval_pdf at fixed (wi, wo) lanes (wi
uniform, wo half uniform and half within 0.1 of forward scattering, where a peaked lobe
changes most with g) and c_l ∈ [0.5, 1.5] fixed: the derivative a differentiable volumetric
path tracer uses for a phase-sampled or light-sampled direction (``sample``'s weight of an
exactly sampled phase function is the constant 1, hg.cpp line 89, and carries none).  The
verdict is the emitter topic's, reused as it is (:func:`phonglab.validate.gradient.verdict`,
the same derivation as the BSDF topic's): forward-mode AD along v (v_i = |x_i|), FD steps from
2⁻⁷ halved until the sums agree, lanes with a jump or kink left out, tolerance
4|D(h) − D(h/2)| + 64u(Σ|S|/h + Σ|∂S|).  Its "sample" there is a fixed direction: the
adapter :class:`_Fixed` returns (wo, value(wo)) as the sample and value(wo) as the arriving
value, so the held sampling factor is 1 and both sides are S(x).
"""

from __future__ import annotations

from types import SimpleNamespace

import drjit as dr
import mitsuba as mi
import numpy as np

from ...verdict import NOT_APPLICABLE
from ... import probe
from ..gradient import verdict
from . import lanes
from .config import rng
from .topics import Row


class _Fixed:
    """The emitter verdict's view of a phase function at fixed directions wo."""

    def __init__(self, phase):
        self.phase = lanes.view(phase)

    def sample_direction(self, it, wo):
        return wo, self.eval_direction(it, wo)

    def eval_direction(self, it, wo):
        value, _ = self.phase.eval_pdf(lanes.context(), it, wo)
        return value


def _phase_row(row) -> Row:
    """The emitter verdict's row in this kind's words."""
    reason = (row.reason.replace("sample_direction weight", "eval_pdf value")
              .replace("Σ c·w₀·eval_direction(ds₀)/e₀ (samples held)", "the same sum")
              .replace("sample_direction's weight", "eval_pdf's value"))
    return Row("gradient", row.name, row.measured, row.expected, row.stderr, row.tolerance,
               row.status, reason, row.details)


def gradient(phase, opts) -> list[Row]:
    if not dr.is_diff_v(mi.Float):
        return [Row("gradient", "AD derivatives", None, None, None, None, "skipped",
                    f"{mi.variant()} has no automatic differentiation: use an llvm_ad_* variant",
                    {NOT_APPLICABLE: True})]
    params = mi.traverse(phase)
    skip = int(mi.ParamFlags.NonDifferentiable) | int(mi.ParamFlags.ReadOnly)
    keys = [k for k in params.keys() if not params.properties[k][3] & skip]
    if not keys:
        return [Row("gradient", "AD derivatives", None, None, None, None, "skipped",
                    "mi.traverse exposes no differentiable parameter", {NOT_APPLICABLE: True})]
    r = rng(opts.seed, "gradient")
    n = opts.gradient_lanes
    wi = lanes.sphere(r, n)
    wo = lanes.sphere(r, n)[::-1].copy()
    d = -wi[: n // 2] + 0.1 * lanes.sphere(r, n // 2)
    wo[: n // 2] = d / np.linalg.norm(d, axis=1)[:, None]
    setup = SimpleNamespace(emitter=_Fixed(phase), calls=_Fixed(phase))
    it, u, c = lanes.interaction(wi), probe.to_vectors(wo), 0.5 + r.random(n)
    return [_phase_row(verdict(setup, params, key, it, u, c, "phase function"))
            for key in keys]
