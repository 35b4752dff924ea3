r"""The ``gradient`` topic: Dr.Jit's derivative of ``eval`` against a central finite difference.

For each differentiable parameter x of ``mi.traverse(bsdf)`` (floats, colours, texture data;
others are skipped with the reason), the functional S(x) = Σ_lanes Σ_channels c_l eval(ω_i, ω_o)
over fixed random directions (ω_o on the whole sphere) and fixed weights c_l ∈ [0.5, 1.5]:

* AD: forward mode from x along the direction v = (1, ..., 1) (``dr.forward``), the lanes'
  gradients summed in float64;
* FD: D(h) = (S(x + h v) − S(x − h v)) / 2h with h = 2⁻⁷ max(|x|, 0.1), and D(h/2);
  a parameter with 0 ≤ x < 2h (a weight or reflectance at 0, where x − h is outside its
  domain and plugins may switch a lobe off) gets the second-order one-sided difference
  (−3S(x) + 4S(x + hv) − S(x + 2hv))/2h instead.

Tolerance, by analysis of float32: the FD truncation error of D(h/2) is about
|D(h) − D(h/2)|/3 (Richardson: the error is O(h²)), taken ×12 (4 |D(h) − D(h/2)|); each eval
lane carries a relative round-off ≤ 64 u (u = 2⁻²⁴), so S(x ± hv) differ from the exact values
by ≤ 64 u Σ|eval| and the quotient by ≤ 64 u Σ|eval|/h; the AD sum adds ≤ 64 u Σ|∂eval|.
A derivative that is wrong by a factor (×2: the planted defect) is off by |D|, far above that.
Needs an AD variant (``llvm_ad_*``/``cuda_ad_*``); elsewhere the topic is one skipped row.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

from .. import probe
from . import lanes
from .config import EPS32
from .report import Row

#: Round-off multiplier of a float32 eval lane (see the module docstring).
ROUND_OFF = 64 * EPS32


def _directions(opts):
    r = lanes.rng(opts.seed, "gradient")
    n = opts.gradient_lanes
    wi = lanes.sphere(r, n)
    wi[:, 2] = np.abs(wi[:, 2]) + 0.05
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    return wi, lanes.sphere(r, n), 0.5 + r.random(n)


def _s(bsdf, wi, wo, c) -> tuple[float, float]:
    ev = probe.eval(bsdf, wi, wo)
    ok = np.isfinite(ev)
    ev = np.where(ok, ev, 0.0)
    return float(np.sum(c[:, None] * ev)), float(np.sum(np.abs(c[:, None] * ev)))


def _set(params, key, value):
    params[key] = value
    params.update()


def _ad(bsdf, params, key, wi, wo, c) -> tuple[float, float]:
    x = params[key]
    dr.enable_grad(x)
    params.update()
    try:
        out = bsdf.eval(probe.context(), probe.interaction(wi), probe.to_vectors(wo))
        dr.forward(x)
        g = probe.to_numpy(dr.grad(out), len(wi))
    finally:
        dr.disable_grad(x)
        params.update()
    g = np.where(np.isfinite(g), g, 0.0)
    return float(np.sum(c[:, None] * g)), float(np.sum(np.abs(c[:, None] * g)))


def _fd(bsdf, params, key, x0, h, wi, wo, c, one_sided: bool) -> float:
    """Central difference, or the second-order one-sided (−3S(x) + 4S(x+h) − S(x+2h))/2h."""
    steps = (0.0, 1.0, 2.0) if one_sided else (1.0, -1.0)
    values = []
    for k in steps:
        _set(params, key, x0 + k * h)
        values.append(_s(bsdf, wi, wo, c)[0])
    _set(params, key, x0)
    if one_sided:
        return (-3.0 * values[0] + 4.0 * values[1] - values[2]) / (2.0 * h)
    return (values[0] - values[1]) / (2.0 * h)


def _one(bsdf, params, key, opts, dirs) -> Row:
    x0 = params[key]
    if not dr.is_diff_v(x0) or dr.type_v(x0) not in (dr.VarType.Float32, dr.VarType.Float64):
        return Row("gradient", key, None, None, None, None, "skipped",
                   f"{type(x0).__name__} is not a differentiable floating-point value", {})
    x0 = type(x0)(x0)                                # a detached copy to restore
    scale = max(float(np.max(np.abs(np.array(x0)))) if dr.width(x0) else 0.0, 0.1)
    h = 2.0 ** -7 * scale
    lo = float(np.min(np.array(x0))) if dr.width(x0) else 0.0
    one_sided = 0.0 <= lo < 2.0 * h        # a non-negative parameter at (or near) 0: stay ≥ 0
    wi, wo, c = dirs
    try:
        ad, ad_abs = _ad(bsdf, params, key, wi, wo, c)
        d1 = _fd(bsdf, params, key, x0, h, wi, wo, c, one_sided)
        d2 = _fd(bsdf, params, key, x0, h / 2, wi, wo, c, one_sided)
    except Exception as exc:   # a plugin refusing x ± h (its validation) is a skip, not a fail
        _set(params, key, x0)
        return Row("gradient", key, None, None, None, None, "skipped",
                   f"the BSDF refused the update x ± {h:.3g}: {str(exc).splitlines()[0][:160]}", {})
    _, s_abs = _s(bsdf, wi, wo, c)
    tol = 4.0 * abs(d1 - d2) + ROUND_OFF * (s_abs / (h / 2) + ad_abs)
    ok = np.isfinite(ad) and abs(ad - d2) <= tol
    return Row("gradient", key, ad, d2, abs(d1 - d2) / 3.0, tol, "pass" if ok else "fail",
               f"forward-mode AD of Σ c·eval along (1,...,1) vs "
               f"{'one-sided (x ≥ 0 at 0)' if one_sided else 'central'} difference "
               f"h = {h / 2:.3g} over {len(wi)} lanes; tolerance 4|D(h)−D(h/2)| + "
               f"64u(Σ|eval|/h + Σ|∂eval|)",
               {"fd_h": d1, "fd_h2": d2, "h": h / 2})


def gradient(bsdf, opts) -> list[Row]:
    if not dr.is_diff_v(mi.Float):
        return [Row("gradient", "AD derivatives", None, None, None, None, "skipped",
                    f"{mi.variant()} has no automatic differentiation: use an llvm_ad_* variant",
                    {})]
    params = mi.traverse(bsdf)
    keys = list(params.keys())
    if not keys:
        return [Row("gradient", "AD derivatives", None, None, None, None, "skipped",
                    "mi.traverse exposes no parameter", {})]
    dirs = _directions(opts)
    rows = []
    for key in keys:
        if params.properties[key][3] & int(mi.ParamFlags.NonDifferentiable):
            rows.append(Row("gradient", key, None, None, None, None, "skipped",
                            "flagged non-differentiable by the plugin (ParamFlags)", {}))
        else:
            rows.append(_one(bsdf, params, key, opts, dirs))
    return rows
