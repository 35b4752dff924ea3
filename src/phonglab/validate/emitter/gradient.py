r"""The ``gradient`` topic: Dr.Jit's derivative of the sampled radiance / intensity against a
central finite difference, for every differentiable parameter ``mi.traverse`` exposes
(radiance, intensity, irradiance, an envmap's data, a spot's cutoff_angle and beam_width).

The functional S(x) = Σ_lanes c_l Σ_channels weight_l, the weights of ``sample_direction``
from the reference points (:func:`~.setup.ref_groups`) with fixed sample values, c_l ∈ [0.5,
1.5] fixed.  As in :mod:`phonglab.validate.bsdf.gradient` (the same derivation): the direction
v_i = |x_i| (max |x| or 0.1 where x_i = 0); AD forward mode (``dr.forward_to``); FD
D(h) = (S(x + hv) − S(x − hv))/2h with h = 2⁻⁷ and D(h/2); lanes whose quotients do not
converge (|D_l(h) − D_l(h/2)| > 1 % + 4× the round-off bound: a jump moving with x), or
whose one-sided quotients at h/2 disagree (|D⁺_l − D⁻_l| > 1 % + 8× the bound: a kink within
h/2 of x, e.g. a spot lane just outside its cutoff, lit for a larger cutoff_angle only, whose
central quotient is half the one-sided slope at any step while AD gives the left one, 0),
are left out and counted; tolerance on the kept sums
4|D(h) − D(h/2)| + 64u(Σ|S_l|/h + Σ|∂S_l|).  The weight is evaluated before the parameter
update is undone, and x is written as an opaque value so the kernels compile once.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

from ... import probe
from ..bsdf.config import EPS32
from .config import rng
from .lanes import with_edges
from .setup import Setup, interaction, point2, ref_groups
from .topics import Row

ROUND_OFF = 64 * EPS32


def _lanes(setup: Setup, it, u, c) -> np.ndarray:
    _, w = setup.emitter.sample_direction(it, u)
    x = probe.to_numpy(w, len(c))
    return c * np.sum(np.where(np.isfinite(x), x, 0.0), axis=1)


def _set(params, key, value):
    value = type(value)(value)
    dr.make_opaque(value)
    params[key] = value
    params.update()


def _one(setup, params, key, it, u, c) -> Row:
    x0 = params[key]
    if not dr.is_diff_v(x0) or dr.type_v(x0) not in (dr.VarType.Float32, dr.VarType.Float64):
        return Row("gradient", key, None, None, None, None, "skipped",
                   f"{type(x0).__name__} is not a differentiable floating-point value", {})
    x0 = type(x0)(x0)
    values = np.array(x0).ravel() if dr.width(x0) else np.zeros(1)
    fill = max(float(np.max(np.abs(values))), 0.1)
    v = dr.detach(dr.select(x0 != 0, dr.abs(x0), fill))
    h = 2.0 ** -7
    try:
        x = params[key]
        dr.enable_grad(x)
        params.update()
        try:
            dr.set_grad(x, v)
            _, w = setup.emitter.sample_direction(it, u)
            dr.forward_to(w)
            g = c * np.sum(probe.to_numpy(dr.grad(w), len(c)), axis=1)
        finally:             # a parameter left tracked would add its derivative to the next's
            dr.disable_grad(x)
            params.update()
        fd = []
        for step in (h, h / 2):
            s = []
            for k in (1.0, -1.0):
                _set(params, key, x0 + (k * step) * v)
                s.append(_lanes(setup, it, u, c))
            fd.append((s[0] - s[1]) / (2.0 * step))
        _set(params, key, x0)
        s0 = _lanes(setup, it, u, c)
        one_sided = ((s[0] - s0) / (h / 2), (s0 - s[1]) / (h / 2))   # at the step h/2
    except Exception as exc:
        _set(params, key, x0)
        if "does not depend on the input" in str(exc):
            return Row("gradient", key, None, None, None, None, "skipped",
                       "sample_direction's weight does not depend on this parameter (Dr.Jit: "
                       "the output does not depend on it; e.g. a spot's texture when none is "
                       "given)", {})
        return Row("gradient", key, None, None, None, None, "skipped",
                   f"the emitter refused the update x ± {h:g}·v: "
                   f"{(str(exc).splitlines() or [type(exc).__name__])[0][:160]}", {})
    d1, d2 = fd
    s_abs = np.abs(_lanes(setup, it, u, c))
    noise = ROUND_OFF * (s_abs / (h / 2) + np.abs(g))
    nonfinite = ~np.isfinite(g)
    scale = 0.01 * np.maximum(np.abs(d2), np.abs(g))
    forward, backward = one_sided
    jumps = ((np.abs(d1 - d2) > scale + 4.0 * noise)
             | (np.abs(forward - backward) > scale + 8.0 * noise)) & ~nonfinite
    keep = ~jumps & ~nonfinite & np.isfinite(d1) & np.isfinite(d2)
    ad, f1, f2 = float(g[keep].sum()), float(d1[keep].sum()), float(d2[keep].sum())
    details = {"fd_h": f1, "fd_h2": f2, "h": h / 2, "lanes": len(g),
               "jump_lanes": int(jumps.sum()), "nonfinite_ad_lanes": int(nonfinite.sum())}
    if keep.sum() < len(g) // 2:
        return Row("gradient", key, ad, f2, None, None, "skipped",
                   f"the difference quotients do not converge on {int(jumps.sum())} of {len(g)} "
                   f"lanes: nothing to compare", details)
    tol = 4.0 * abs(f1 - f2) + float(noise[keep].sum())
    ok = np.isfinite(ad) and abs(ad - f2) <= tol
    return Row("gradient", key, ad, f2, abs(f1 - f2) / 3.0, tol, "pass" if ok else "fail",
               f"forward-mode AD of Σ c·(sample_direction weight) along v (v_i = |x_i|) vs the "
               f"central difference with step {h / 2:g}·v over {int(keep.sum())} lanes "
               f"({int(jumps.sum())} with a jump, {int(nonfinite.sum())} with a non-finite AD "
               f"derivative left out); tolerance 4|D(h)−D(h/2)| + 64u(Σ|S|/h + Σ|∂S|)", details)


def gradient(setup: Setup, opts) -> list[Row]:
    if not dr.is_diff_v(mi.Float):
        return [Row("gradient", "AD derivatives", None, None, None, None, "skipped",
                    f"{mi.variant()} has no automatic differentiation: use an llvm_ad_* variant",
                    {})]
    params = mi.traverse(setup.emitter)
    keys = [k for k in params.keys()
            if not params.properties[k][3] & int(mi.ParamFlags.NonDifferentiable)]
    if not keys:
        return [Row("gradient", "AD derivatives", None, None, None, None, "skipped",
                    "mi.traverse exposes no differentiable parameter", {})]
    n = max(1, opts.gradient_lanes // 4)
    groups = ref_groups(setup, n, opts.seed)
    p = np.concatenate([g.p for g in groups])
    r = rng(opts.seed, "gradient")
    it = interaction(p)
    u = point2(with_edges(r.random((len(p), 2)), n))
    c = 0.5 + r.random(len(p))
    return [_one(setup, params, key, it, u, c) for key in keys]
