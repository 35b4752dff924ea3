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

Lanes along which no radiance arrives at x (e₀ = 0: an emitter swept to an emitted quantity
of 0) while the weight's derivative is not 0 have no sampling factor (0/0) and are left out;
where they are most lanes the row is skipped, saying so.  The step, its halving, the other
lanes left out (jumps, kinks) and the tolerance are every kind's:
:func:`phonglab.validate.gradient.verdict`.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

from ...verdict import NOT_APPLICABLE
from ... import probe
from ..gradient import MAX_HALVINGS, differentiable_keys, verdict, without_ad
from .config import rng
from .lanes import with_edges
from .setup import Setup, interaction, point2, ref_groups
from .topics import Row


class HeldSampling:
    """The :class:`~phonglab.validate.gradient.Functional` of the module docstring: AD of
    Σ c·weight, FD of Σ c·w₀·eval_direction(ds₀)/e₀ with ds₀ and w₀/e₀ held at x."""

    ad_words = "Σ c·(sample_direction weight)"
    fd_words = "Σ c·w₀·eval_direction(ds₀)/e₀ (samples held)"
    what = "sample_direction's weight"
    owner = "emitter"
    undefined_words = "no radiance arrives along the sample (the emitted quantity is 0)"
    max_halvings = MAX_HALVINGS
    kinks = True

    def __init__(self, setup: Setup, it, u, c: np.ndarray):
        self.calls, self.it, self.u, self.c = setup.calls, it, u, c
        self.ds = self.ratio = None

    def _sum(self, x, finite_only: bool) -> np.ndarray:
        if finite_only:
            x = np.where(np.isfinite(x), x, 0.0)
        return self.c * np.sum(x, axis=1)

    def derivative(self) -> np.ndarray:
        _, w = self.calls.sample_direction(self.it, self.u)
        dr.forward_to(w)
        return self._sum(probe.to_numpy(dr.grad(w), len(self.c)), False)

    def hold(self) -> None:
        """ds₀ = sample_direction at x (evaluated, no gradient) and the sampling factor w₀/e₀
        per channel, e₀ = eval_direction(ds₀)."""
        n = len(self.c)
        ds, w = self.calls.sample_direction(self.it, self.u)
        self.ds = dr.detach(ds)
        dr.eval(self.ds)
        w0 = probe.to_numpy(w, n)
        e0 = probe.to_numpy(self.calls.eval_direction(self.it, self.ds), n)
        self.ratio = np.where((e0 != 0) & np.isfinite(w0), w0 / np.where(e0 != 0, e0, 1.0), 0.0)

    def lanes(self) -> np.ndarray:
        x = probe.to_numpy(self.calls.eval_direction(self.it, self.ds), len(self.c)) * self.ratio
        return self._sum(x, True)

    def undefined(self, g: np.ndarray) -> np.ndarray:
        """Lanes with no arriving radiance at x (e₀ = 0 in every channel) whose weight has a
        derivative: the held factor w₀/e₀ is 0/0 there."""
        ds, _ = self.calls.sample_direction(self.it, self.u)
        e0 = probe.to_numpy(self.calls.eval_direction(self.it, dr.detach(ds)), len(self.c))
        return np.all(e0 == 0, axis=1) & (g != 0)


def gradient(setup: Setup, opts) -> list[Row]:
    skipped = without_ad(Row)
    if skipped:
        return skipped
    params = mi.traverse(setup.emitter)
    keys = differentiable_keys(params)
    if not keys:
        return [Row("gradient", "AD derivatives", None, None, None, None, "skipped",
                    "mi.traverse exposes no differentiable parameter", {NOT_APPLICABLE: True})]
    n = max(1, opts.gradient_lanes // 4)
    groups = ref_groups(setup, n, opts.seed)
    p = np.concatenate([g.p for g in groups])
    r = rng(opts.seed, "gradient")
    u = point2(with_edges(r.random((len(p), 2)), n))
    c = 0.5 + r.random(len(p))
    fn = HeldSampling(setup, interaction(p), u, c)
    return [verdict(fn, params, key, row=Row) for key in keys]
