r"""The ``gradient`` topic: Dr.Jit's derivative of ``eval`` against a central finite difference.

For each differentiable parameter x of ``mi.traverse(bsdf)`` (floats, colours, texture data;
others are skipped with the reason), the functional S(x) = Σ_lanes Σ_channels c_l eval(ω_i, ω_o)
over fixed random directions (ω_o on the whole sphere) and fixed weights c_l ∈ [0.5, 1.5]:

* the direction v scales each element: v_i = |x_i|, or max(max_j |x_j|, 0.1) where x_i = 0,
  so that every element moves by the same relative step (a spectral ``rgb`` texture holds
  polynomial coefficients of very different sizes, e.g. (−7.5e-5, 0.082, −22.5));
* AD: forward mode from x with gradient v (``dr.set_grad`` + ``dr.forward_to``), the lanes'
  gradients summed in float64;
* FD: D(h) = (S(x + h v) − S(x − h v)) / 2h with h = 2⁻⁷, and D(h/2); a non-negative
  parameter with an element at 0 (a weight or reflectance at 0, where x − hv leaves its domain
  and plugins may switch a lobe off) gets the second-order one-sided difference
  (−3S(x) + 4S(x + hv) − S(x + 2hv))/2h instead;
* lanes whose quotients do not converge (|D_l(h) − D_l(h/2)| > 1 % of |D_l(h/2)| + 4× the
  lane's round-off bound, judged from the quotients alone: :func:`..gradient.unconverged`)
  hold a jump or a kink that moves with x (e.g.
  roughdielectric's total-internal-reflection boundary under eta, a parameter flagged
  ``ParamFlags.Discontinuous``): there AD differentiates the continuous part only, by
  Mitsuba's design, so those lanes are left out and counted, as are lanes whose AD derivative
  is not finite (e.g. √ at 0 at a critical angle); when they are the majority the row is
  skipped.

Tolerance on the kept lanes' sums, by analysis of float32: the FD truncation error of D(h/2) is about
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

from ...verdict import NOT_APPLICABLE
from ... import probe
from . import lanes
from ..gradient import unconverged
from ..roundoff import EPS32
from .topics import Row

#: Round-off multiplier of a float32 eval lane (see the module docstring).
ROUND_OFF = 64 * EPS32


def _directions(opts):
    r = lanes.rng(opts.seed, "gradient")
    n = opts.gradient_lanes
    wi = lanes.sphere(r, n)
    wi[:, 2] = np.abs(wi[:, 2]) + 0.05
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    return wi, lanes.sphere(r, n), 0.5 + r.random(n)


def _lanes(bsdf, wi, wo, c) -> np.ndarray:
    """Per lane: c_l Σ_channels eval (non-finite values as 0)."""
    ev = probe.eval(bsdf, wi, wo)
    return c * np.sum(np.where(np.isfinite(ev), ev, 0.0), axis=1)


def _set(params, key, value):
    """Write x ± h as an opaque value: a kernel input, so the BSDF's kernels compile once
    for all steps instead of once per baked-in literal."""
    value = type(value)(value)
    dr.make_opaque(value)
    params[key] = value
    params.update()


def _ad(bsdf, params, key, v, wi, wo, c) -> np.ndarray:
    """Per lane: the forward-mode derivative of c·Σ eval along v.  Leaves ``key`` detached but
    not yet re-propagated: the caller's next :func:`_set` updates (an update costs ~30 ms for
    a BSDF that tabulates in ``parameters_changed``, roughplastic; 8 a parameter were 5)."""
    x = params[key]
    dr.enable_grad(x)
    params.update()
    try:
        dr.set_grad(x, v)
        out = probe.view(bsdf).eval(probe.context(), probe.interaction(wi), probe.to_vectors(wo))
        dr.forward_to(out)
        g = probe.to_numpy(dr.grad(out), len(wi))
    finally:
        dr.disable_grad(x)
    return c * np.sum(g, axis=1)            # NaN/Inf kept: the caller counts those lanes


def _fd(bsdf, params, key, x0, v, h, wi, wo, c, one_sided: bool,
        restore: bool = True) -> np.ndarray:
    """Derivative along v: central (S(x+hv) − S(x−hv))/2h, or the second-order one-sided
    (−3S(x) + 4S(x+hv) − S(x+2hv))/2h.  ``restore``: write x back afterwards (False when the
    caller's next step writes another value anyway)."""
    steps = (0.0, 1.0, 2.0) if one_sided else (1.0, -1.0)
    values = []
    for k in steps:
        _set(params, key, x0 + (k * h) * v)
        values.append(_lanes(bsdf, wi, wo, c))
    if restore:
        _set(params, key, x0)
    if one_sided:
        return (-3.0 * values[0] + 4.0 * values[1] - values[2]) / (2.0 * h)
    return (values[0] - values[1]) / (2.0 * h)


def _first(exc) -> str:
    return (str(exc).splitlines() or [type(exc).__name__])[0][:160]


def _refused(key, h, exc) -> Row:
    return Row("gradient", key, None, None, None, None, "skipped",
               f"the validator's own finite-difference step x ± {h:g}·v left the values the "
               f"BSDF accepts (it raised: {_first(exc)}): a limit of the check's step, not a "
               f"defect of the BSDF", {})


def _independent(bsdf, params, key, x0, v, h, dirs, one_sided: bool) -> Row:
    """Dr.Jit found no dependence of eval on ``key`` (forward_to raised).  This topic
    differentiates eval, which is 0 for a delta lobe (conductor, thindielectric, polarizer):
    when the differences of eval are 0 too there is nothing to compare (skipped, the check's
    limit, not the BSDF's); when they are not, AD lost a dependence eval has: a fail."""
    wi, wo, c = dirs
    try:
        d2 = _fd(bsdf, params, key, x0, v, h / 2, wi, wo, c, one_sided)
    except Exception as exc:
        _set(params, key, x0)
        return _refused(key, h, exc)
    noise = float((ROUND_OFF * np.abs(_lanes(bsdf, wi, wo, c)) / (h / 2)).sum())
    fd = float(np.nansum(d2))
    details = {"fd_h2": fd, "h": h / 2, "one_sided": one_sided, "lanes": int(len(d2))}
    if abs(fd) <= noise:
        return Row("gradient", key, None, None, None, None, "skipped",
                   "eval, which this topic differentiates, does not depend on this parameter "
                   "at the probed directions (Dr.Jit finds no dependence and the finite "
                   "differences are 0 too; a delta lobe's eval is 0): nothing to compare, a "
                   "limit of the check, not a defect of the BSDF", details)
    return Row("gradient", key, 0.0, fd, None, noise, "fail",
               f"forward-mode AD finds no dependence of eval on this parameter (drjit."
               f"forward_to raised) while its finite difference with step {h / 2:g}·v is "
               f"{fd:.6g}: AD lost a dependence eval has", details)


def _one(bsdf, params, key, opts, dirs, discontinuous: bool) -> Row:
    try:
        x0 = params[key]
    except TypeError as exc:   # e.g. hair's sigma_a is traversed as None when unused
        return Row("gradient", key, None, None, None, None, "skipped",
                   f"mi.traverse exposes a value that cannot be read ({_first(exc)})", {})
    if not dr.is_diff_v(x0) or dr.type_v(x0) not in (dr.VarType.Float32, dr.VarType.Float64):
        return Row("gradient", key, None, None, None, None, "skipped",
                   f"{type(x0).__name__} is not a differentiable floating-point value", {})
    x0 = type(x0)(x0)                                # a detached copy to restore
    values = np.array(x0).ravel() if dr.width(x0) else np.zeros(1)
    fill = max(float(np.max(np.abs(values))), 0.1)
    v = dr.detach(dr.select(x0 != 0, dr.abs(x0), fill))
    h = 2.0 ** -7
    one_sided = bool(values.min() >= 0.0 and (values == 0.0).any())
    wi, wo, c = dirs
    try:
        g = _ad(bsdf, params, key, v, wi, wo, c)
    except Exception as exc:
        if "does not depend on the input" not in str(exc):
            _set(params, key, x0)
            return _refused(key, h, exc)
        return _independent(bsdf, params, key, x0, v, h, dirs, one_sided)
    try:
        d1 = _fd(bsdf, params, key, x0, v, h, wi, wo, c, one_sided, restore=False)
        d2 = _fd(bsdf, params, key, x0, v, h / 2, wi, wo, c, one_sided)
    except Exception as exc:   # a plugin refusing x ± hv (its validation) is a skip, not a fail
        _set(params, key, x0)
        return _refused(key, h, exc)
    s_abs = np.abs(_lanes(bsdf, wi, wo, c))
    noise = ROUND_OFF * (s_abs / (h / 2) + np.abs(g))          # per-lane round-off bound
    nonfinite = ~np.isfinite(g)
    jumps = unconverged(d1, d2, noise) & ~nonfinite
    keep = ~jumps & ~nonfinite & np.isfinite(d1) & np.isfinite(d2)
    ad, fd1, fd2 = float(g[keep].sum()), float(d1[keep].sum()), float(d2[keep].sum())
    details = {"fd_h": fd1, "fd_h2": fd2, "h": h / 2, "one_sided": one_sided,
               "value_range": [float(values.min()), float(values.max())],
               "lanes": int(len(g)), "jump_lanes": int(jumps.sum()),
               "nonfinite_ad_lanes": int(nonfinite.sum()),
               "discontinuous_flag": discontinuous,
               "all_lanes": {"ad": float(np.nansum(g)), "fd_h2": float(np.nansum(d2))}}
    if keep.sum() < len(g) // 2:   # mostly jumps or NaN derivatives: no derivative to compare
        return Row("gradient", key, ad, fd2, None, None, "skipped",
                   f"the difference quotients do not converge on {int(jumps.sum())} of "
                   f"{len(g)} lanes (a discontinuity moving with the parameter"
                   f"{', flagged Discontinuous' if discontinuous else ''}): nothing to compare",
                   details)
    tol = 4.0 * abs(fd1 - fd2) + float(noise[keep].sum())
    ok = np.isfinite(ad) and abs(ad - fd2) <= tol
    return Row("gradient", key, ad, fd2, abs(fd1 - fd2) / 3.0, tol, "pass" if ok else "fail",
               f"forward-mode AD of Σ c·eval along v (v_i = |x_i|) vs "
               f"{'one-sided (x ≥ 0 with an element at 0)' if one_sided else 'central'} "
               f"difference with step {h / 2:g}·v over {int(keep.sum())} lanes "
               f"({int(jumps.sum())} lanes with a jump and {int(nonfinite.sum())} with a "
               f"non-finite AD derivative left out); tolerance "
               f"4|D(h)−D(h/2)| + 64u(Σ|eval|/h + Σ|∂eval|)", details)


def gradient(bsdf, opts) -> list[Row]:
    if not dr.is_diff_v(mi.Float):
        return [Row("gradient", "AD derivatives", None, None, None, None, "skipped",
                    f"{mi.variant()} has no automatic differentiation: use an llvm_ad_* variant",
                    {NOT_APPLICABLE: True})]
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
    dirs = _directions(opts)
    rows = []
    for key in keys:
        flags = params.properties[key][3]
        if flags & int(mi.ParamFlags.NonDifferentiable):
            rows.append(Row("gradient", key, None, None, None, None, "skipped",
                            "flagged non-differentiable by the plugin (ParamFlags)",
                            {NOT_APPLICABLE: True}))
        else:
            rows.append(_one(bsdf, params, key, opts, dirs,
                             bool(flags & int(mi.ParamFlags.Discontinuous))))
    return rows
