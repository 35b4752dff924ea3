r"""The ``gradient`` topic: Dr.Jit's derivative of a medium's coefficients against a central
finite difference, for every differentiable parameter ``mi.traverse`` exposes (homogeneous's
``albedo`` and ``sigma_t`` values, heterogeneous's grid data; a Python medium's own).

What a differentiable volumetric path tracer differentiates (prbvolpath.py at v3.9.1): the
coefficients ``get_scattering_coefficients`` returns at each interaction, σ_s (the scattering
weight, prbvolpath.py:207-214) and σ_t (through the real-collision probability and the
transmittance weight), σ_n = σ̄ − σ_t with them.  So, per parameter x and per coefficient
σ ∈ {σ_s, σ_t}, S(x) = Σ_lanes c_l Σ_channels σ_l(x) at fixed interactions (the probe's
in-bounds points, :meth:`.lanes.Probe.points`: uniform ones and those ``sample_interaction``
chose) with c_l ∈ [0.5, 1.5] fixed.  Two rows per parameter, so that a derivative wrong in one
coefficient is not hidden by the other's.

The verdict is every kind's (:func:`phonglab.validate.gradient.verdict`): forward-mode AD along
v (v_i = |x_i|), FD steps from 2⁻⁷ halved until the sums agree, lanes with a jump or kink left
out, AD finding no dependence judged against the differences (a fail where they are not 0),
tolerance 4|D(h) − D(h/2)| + 64u(Σ|S|/h + Σ|∂S|).

Parameters of the medium's phase function (``phase_function.*``) are the ``phase`` topic's
(the phase kind's own ``gradient``); parameters flagged non-differentiable or read-only are
left out, as Mitsuba's optimizers leave them.
"""

from __future__ import annotations

import mitsuba as mi
import numpy as np

from ...verdict import NOT_APPLICABLE
from ..gradient import AtFixedInputs, differentiable_keys, verdict, without_ad
from . import lanes
from .config import rng
from .topics import Row

#: The coefficients differentiated, by their index in get_scattering_coefficients' tuple.
COEFFICIENTS = {"σ_s": 0, "σ_t": 2}


def gradient(medium, opts) -> list[Row]:
    skipped = without_ad(Row)
    if skipped:
        return skipped
    params = mi.traverse(medium)
    keys = [k for k in differentiable_keys(params) if not k.startswith("phase_function.")]
    if not keys:
        return [Row("gradient", "AD derivatives", None, None, None, None, "skipped",
                    "mi.traverse exposes no differentiable parameter of the medium (its phase "
                    "function's are the phase topic's)", {NOT_APPLICABLE: True})]
    points = lanes.probe(medium, opts).points()
    if not len(points["t"]):
        return [Row("gradient", "AD derivatives", None, None, None, None, "skipped",
                    "no probe ray meets the medium's bounds: no interaction to differentiate "
                    "at (the bounds topic says where they are)", {NOT_APPLICABLE: True})]
    r = rng(opts.seed, "gradient")
    pick = r.choice(len(points["t"]), min(opts.gradient_lanes, len(points["t"])), replace=False)
    it = lanes.interaction(points["o"][pick], points["d"][pick], points["t"][pick])
    plugin, active, c = lanes.view(medium), mi.Bool(True), 0.5 + r.random(len(pick))
    rows = []
    for key in keys:
        for name, index in COEFFICIENTS.items():
            fn = AtFixedInputs(
                lambda index=index: plugin.get_scattering_coefficients(it, active)[index], c,
                f"Σ c·{name}", name, "medium")
            row = verdict(fn, params, key, row=Row)
            row.name = f"{key}: {name}"
            rows.append(row)
    return rows
