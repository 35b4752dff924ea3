r"""The AD-against-finite-difference verdict of one parameter, for every kind: Dr.Jit's forward-mode
derivative of a functional S(x) = Σ_lanes S_l(x) against difference quotients of the same sum.

Each kind's ``gradient`` topic states its functional (a :class:`Functional`): the BSDF's
Σ c·eval at fixed directions (:mod:`phonglab.validate.bsdf.gradient`), the emitter's sampled
weight with its sampling held (:mod:`phonglab.validate.emitter.gradient`), the phase
function's eval_pdf value and the medium's σ_s and σ_t at fixed points
(:mod:`phonglab.validate.phase.gradient`, :mod:`phonglab.validate.medium.gradient`), with fixed
weights c_l ∈ [0.5, 1.5]; :func:`verdict` judges it for one parameter x of ``mi.traverse``:

* the direction v scales each element: v_i = |x_i|, or max(max_j |x_j|, 0.1) where x_i = 0,
  so that every element moves by the same relative step (a spectral ``rgb`` texture holds
  polynomial coefficients of very different sizes, e.g. (−7.5e-5, 0.082, −22.5));
* AD: forward mode from x with gradient v (``dr.set_grad`` + ``dr.forward_to``), the lanes'
  derivatives in float64;
* FD: D(h) = (S(x + hv) − S(x − hv))/2h and D(h/2); a non-negative parameter with an element at
  0 (a weight or reflectance at 0, where x − hv leaves its domain and plugins may switch a lobe
  off) gets the second-order one-sided difference (−3S(x) + 4S(x + hv) − S(x + 2hv))/2h
  instead.  h starts at 2⁻⁷ and is halved (at most :data:`MAX_HALVINGS` times) until the sums
  Σ D(h) and Σ D(h/2) agree to 1 % + the round-off bound and at least half of the lanes
  converge (a peaked lobe's curvature: hg at g = 0.8 needs a smaller step near forward
  scattering; a spectral variant's ``radiance.value`` holds the coefficients of Mitsuba's
  RGB-to-spectrum model, the first multiplying λ² ≈ 2.5·10⁵, and a step of 2⁻⁷·0.1 drives its
  sigmoid into saturation), but never below the step where the round-off bound reaches
  :data:`ROUND_OFF_SHARE` of the quotients' sum (a conductor's Fresnel term at eta = 0 cancels
  in float32 below eta ~ 1e-4: its differences there are 0 whatever the slope, and a step
  halved into that regime would call AD's 0 right).  The step is chosen from the quotients
  alone, never from AD;
* a kind may keep the step fixed at 2⁻⁷ (the BSDF kind: ``max_halvings`` 0, its conformance
  findings measured so; a conductor's Fresnel term at eta = 0 cancels in float32 below
  eta ~ 1e-4, where a halved step sees its slope as jumps) and judge convergence from D(h) and
  D(h/2) alone (``kinks`` False);
* lanes whose quotients do not converge (:func:`unconverged`: a jump or a kink that moves with
  x, e.g. roughdielectric's total-internal-reflection boundary under eta, a parameter flagged
  ``ParamFlags.Discontinuous``: there AD differentiates the continuous part only, by Mitsuba's
  design) are left out and counted, as are lanes whose AD derivative is not finite (√ at 0 at
  a critical angle) and lanes the functional calls undefined (an emitter's sample along which
  no radiance arrives); when they are the majority the row is skipped, saying why;
* Dr.Jit finding no dependence on x (``forward_to`` raises) is a skip when the differences
  are 0 too (a delta lobe's eval is 0; a spot's texture when none is given) and a fail when
  they are not: AD lost a dependence the function has.

Tolerance on the kept lanes' sums, by analysis of float32: the FD truncation error of D(h/2) is
about |D(h) − D(h/2)|/3 (Richardson: the error is O(h²)), taken ×12 (4 |D(h) − D(h/2)|); each
lane carries a relative round-off ≤ 64 u (u = 2⁻²⁴), so S(x ± hv) differ from the exact values
by ≤ 64 u Σ|S_l| and the quotient by ≤ 64 u Σ|S_l|/h; the AD sum adds ≤ 64 u Σ|∂S_l|.  A
derivative that is wrong by a factor (×2: the planted defects) is off by |D|, far above that.
x is written as an opaque value (a kernel input: the kernels compile once for all steps) and
restored after each parameter; a plugin that refuses x ± hv (its own validation) makes the row
a skip, the check's limit, not the plugin's defect.
"""

from __future__ import annotations

from typing import Protocol

import drjit as dr
import mitsuba as mi
import numpy as np

from .. import probe
from ..verdict import NOT_APPLICABLE, Row
from .roundoff import EPS32

#: Round-off multiplier of a float32 lane (see the module docstring).
ROUND_OFF = 64 * EPS32
#: The first finite-difference step (relative, along v), and how often it may be halved.
H0 = 2.0 ** -7
MAX_HALVINGS = 16
#: The step is halved only while the round-off bound of the quotients is below this share of
#: their sum: past it the differences measure float32 cancellation, not the derivative, and
#: the bound (∝ 1/h) would grow into a tolerance that passes anything.
ROUND_OFF_SHARE = 0.01


class Functional(Protocol):
    """What a kind's ``gradient`` topic differentiates (module docstring).

    ``lanes()`` is S_l at the parameters as they are now, non-finite lanes as 0 (the FD side);
    ``derivative()`` the forward-mode derivative per lane, called while x carries its
    gradient (non-finite lanes kept: the verdict counts them); ``hold()`` fixes what the FD
    side holds at x (an emitter's samples; may do nothing) and ``undefined()`` the lanes where
    that held factor is undefined (None: none; ``undefined_words`` says why in a row).
    ``ad_words`` and ``fd_words`` say what is compared, ``what`` the differentiated quantity,
    ``owner`` the plugin's kind ("BSDF").  ``max_halvings``: how often the step may be halved
    (0: the fixed step 2⁻⁷); ``kinks``: whether lanes whose one-sided quotients disagree are
    left out too."""

    max_halvings: int
    kinks: bool
    ad_words: str
    fd_words: str
    what: str
    owner: str
    undefined_words: str

    def lanes(self) -> np.ndarray: ...

    def derivative(self) -> np.ndarray: ...

    def hold(self) -> None: ...

    def undefined(self, g: np.ndarray) -> np.ndarray | None: ...


def without_ad(row=Row) -> list | None:
    """The topic's one skipped row (of the kind's ``row`` type) in a variant without automatic
    differentiation; None in an AD variant."""
    if dr.is_diff_v(mi.Float):
        return None
    return [row("gradient", "AD derivatives", None, None, None, None, "skipped",
                f"{mi.variant()} has no automatic differentiation: use an llvm_ad_* variant",
                {NOT_APPLICABLE: True})]


def differentiable_keys(params) -> list[str]:
    """The keys of ``params`` (``mi.traverse``) an optimizer would differentiate: neither
    flagged non-differentiable nor read-only (traversed for reading, refused on update:
    sunsky's sun_direction when it is computed from a date and place, sunsky.cpp:291)."""
    skip = int(mi.ParamFlags.NonDifferentiable) | int(mi.ParamFlags.ReadOnly)
    return [k for k in params.keys() if not params.properties[k][3] & skip]


def unconverged(d1, d2, noise, forward=None, backward=None) -> np.ndarray:
    """Per lane: the difference quotients cannot judge a derivative there.  D(h) and D(h/2)
    do not converge (|D_l(h) − D_l(h/2)| > 1 % of |D_l(h/2)| + 4× the round-off bound: a
    jump moving with x, or a kink or a √ singularity within h of x), or, given the one-sided
    quotients at h/2, those disagree (> 1 % + 8× the bound: a kink within h/2 of x).

    Judged from the quotients alone, never from AD: a lane's use as a judge of AD must not
    depend on the AD it judges.  (1 % of max(|D_l(h/2)|, |AD_l|) kept, at pplastic's
    η = 0.99972, lanes just above the critical cosine 0.0235 whose AD derivative is 138
    against quotients 0.31 and 0.78 -- the step crosses the total-reflection edge, where
    ∂/∂η of the Fresnel term grows as 1/√(cos² θ − cos² θ_c) -- and the sums read 408
    against 3.4.)  Lanes with a non-finite quotient or AD derivative are the caller's to
    count."""
    scale = 0.01 * np.abs(d2)
    with np.errstate(invalid="ignore"):
        out = np.abs(d1 - d2) > scale + 4.0 * noise
        if forward is not None:
            out |= np.abs(forward - backward) > scale + 8.0 * noise
    return out


def _set(params, key, value) -> None:
    """Write ``value`` as an opaque value (a kernel input) and let the plugin re-derive."""
    value = type(value)(value)
    dr.make_opaque(value)
    params[key] = value
    params.update()


def _ad(fn: Functional, params, key, v) -> np.ndarray:
    """Per lane: the forward-mode derivative along v.  Leaves ``key`` detached but not yet
    re-propagated: the verdict's next :func:`_set` updates (an update costs ~50 ms for a
    plugin that tabulates in ``parameters_changed``, roughplastic's alpha and eta)."""
    x = params[key]
    dr.enable_grad(x)
    params.update()
    try:
        dr.set_grad(x, v)
        return fn.derivative()
    finally:                 # a parameter left tracked would add its derivative to the next's
        dr.disable_grad(x)


def _quotients(fn: Functional, params, key, x0, v, h, one_sided: bool):
    """(D(h), D(h/2), S(x)) per lane, and (D⁺(h/2), D⁻(h/2)) for a central difference (None
    for a one-sided one); x is restored to x0."""
    s0, fd, sides = None, [], None
    for step in (h, h / 2):
        ks = (0.0, 1.0, 2.0) if one_sided else (1.0, -1.0)
        s = {}
        for k in ks:
            if k == 0.0 and s0 is not None:
                s[k] = s0
                continue
            _set(params, key, x0 + (k * step) * v)
            s[k] = fn.lanes()
        if one_sided:
            s0 = s[0.0]
            fd.append((-3.0 * s[0.0] + 4.0 * s[1.0] - s[2.0]) / (2.0 * step))
        else:
            fd.append((s[1.0] - s[-1.0]) / (2.0 * step))
    _set(params, key, x0)
    if not one_sided:
        s0 = fn.lanes()
        sides = ((s[1.0] - s0) / (h / 2), (s0 - s[-1.0]) / (h / 2))
    return fd[0], fd[1], s0, sides


def _first(exc) -> str:
    return (str(exc).splitlines() or [type(exc).__name__])[0][:160]


def _skip(key, reason, details=None, row=Row) -> Row:
    return row("gradient", key, None, None, None, None, "skipped", reason, details or {})


def _refused(fn: Functional, key, h, exc, row=Row) -> Row:
    return _skip(key, f"the validator's own finite-difference step x ± {h:g}·v left the values "
                      f"the {fn.owner} accepts (it raised: {_first(exc)}): a limit of the "
                      f"check's step, not a defect of the {fn.owner}", row=row)


def _independent(fn: Functional, params, key, x0, v, one_sided: bool, row=Row) -> Row:
    """Dr.Jit found no dependence of the functional on ``key``: a skip when the differences
    are 0 too (nothing to compare), a fail when they are not (AD lost a dependence)."""
    h = H0 / 2
    try:
        _, d2, s0, _ = _quotients(fn, params, key, x0, v, H0, one_sided)
    except Exception as exc:
        _set(params, key, x0)
        return _refused(fn, key, H0, exc, row)
    noise = float((ROUND_OFF * np.abs(s0) / h).sum())
    fd = float(np.nansum(d2))
    details = {"fd_h2": fd, "h": h, "one_sided": one_sided, "lanes": int(len(d2))}
    if abs(fd) <= noise:
        return _skip(key, f"{fn.what} does not depend on this parameter (Dr.Jit finds no "
                          f"dependence and the finite differences are 0 too): nothing to "
                          f"compare, a limit of the check, not a defect of the {fn.owner}",
                     details, row)
    return row("gradient", key, 0.0, fd, None, noise, "fail",
               f"forward-mode AD finds no dependence of {fn.what} on this parameter "
               f"(drjit.forward_to raised) while its finite difference with step {h:g}·v is "
               f"{fd:.6g}: AD lost a dependence {fn.what} has", details)


def verdict(fn: Functional, params, key: str, discontinuous: bool = False,
            row=Row) -> Row:
    """One parameter's gradient row (module docstring); ``discontinuous``: the parameter is
    flagged ``ParamFlags.Discontinuous`` (said in a skip); ``row``: the kind's row type."""
    try:
        x0 = params[key]
    except TypeError as exc:   # e.g. hair's sigma_a is traversed as None when unused
        return _skip(key, f"mi.traverse exposes a value that cannot be read ({_first(exc)})",
                     row=row)
    if not dr.is_diff_v(x0) or dr.type_v(x0) not in (dr.VarType.Float32, dr.VarType.Float64):
        return _skip(key, f"{type(x0).__name__} is not a differentiable floating-point value",
                     row=row)
    x0 = type(x0)(x0)                                # a detached copy to restore
    values = np.array(x0).ravel() if dr.width(x0) else np.zeros(1)
    fill = max(float(np.max(np.abs(values))), 0.1)
    v = dr.detach(dr.select(x0 != 0, dr.abs(x0), fill))
    one_sided = bool(values.min() >= 0.0 and (values == 0.0).any())
    h = H0
    try:
        g = _ad(fn, params, key, v)
    except Exception as exc:
        if "does not depend on the input" not in str(exc):
            _set(params, key, x0)
            return _refused(fn, key, h, exc, row)
        return _independent(fn, params, key, x0, v, one_sided, row)
    try:
        fn.hold()
        for halvings in range(fn.max_halvings + 1):
            h = H0 * 2.0 ** -halvings
            d1, d2, s0, sides = _quotients(fn, params, key, x0, v, h, one_sided)
            noise = ROUND_OFF * (np.abs(s0) / (h / 2) + np.abs(g))   # per-lane round-off
            jumps = unconverged(d1, d2, noise, *(sides if fn.kinks and sides else ())) \
                & np.isfinite(g)
            if (abs(np.nansum(d1) - np.nansum(d2)) <= 0.01 * abs(np.nansum(d2)) + noise.sum()
                    and jumps.sum() <= len(g) // 2):
                break
            if noise.sum() >= ROUND_OFF_SHARE * abs(np.nansum(d2)):
                break            # a smaller step would measure round-off, not the derivative
    except Exception as exc:   # a plugin refusing x ± hv (its validation) is a skip
        _set(params, key, x0)
        return _refused(fn, key, h, exc, row)
    nonfinite = ~np.isfinite(g)
    undefined = fn.undefined(g)
    undefined = np.zeros(len(g), bool) if undefined is None else undefined & ~nonfinite
    keep = ~jumps & ~nonfinite & ~undefined & np.isfinite(d1) & np.isfinite(d2)
    ad, f1, f2 = float(g[keep].sum()), float(d1[keep].sum()), float(d2[keep].sum())
    details = {"fd_h": f1, "fd_h2": f2, "h": h / 2, "halvings": halvings,
               "one_sided": one_sided, "value_range": [float(values.min()), float(values.max())],
               "lanes": int(len(g)), "jump_lanes": int(jumps.sum()),
               "nonfinite_ad_lanes": int(nonfinite.sum()),
               "discontinuous_flag": discontinuous,
               "all_lanes": {"ad": float(np.nansum(g)), "fd_h2": float(np.nansum(d2))}}
    left_out = ""
    if undefined.any():
        details["undefined_lanes"] = int(undefined.sum())
        left_out = f", {int(undefined.sum())} where {fn.undefined_words}"
    if keep.sum() < len(g) // 2 and undefined.sum() > jumps.sum():
        return row("gradient", key, ad, f2, None, None, "skipped",
                   f"{fn.undefined_words} on {int(undefined.sum())} of {len(g)} lanes while "
                   f"AD's derivative is not 0 there: the difference side is undefined, nothing "
                   f"to compare", details)
    if keep.sum() < len(g) // 2:
        return row("gradient", key, ad, f2, None, None, "skipped",
                   f"the difference quotients do not converge on {int(jumps.sum())} of "
                   f"{len(g)} lanes (a discontinuity moving with the parameter"
                   f"{', flagged Discontinuous' if discontinuous else ''}): nothing to compare",
                   details)
    tol = 4.0 * abs(f1 - f2) + float(noise[keep].sum())
    ok = np.isfinite(ad) and abs(ad - f2) <= tol
    how = "one-sided (x ≥ 0 with an element at 0)" if one_sided else "central"
    return row("gradient", key, ad, f2, abs(f1 - f2) / 3.0, tol, "pass" if ok else "fail",
               f"forward-mode AD of {fn.ad_words} along v (v_i = |x_i|) vs the {how} "
               f"difference of {fn.fd_words}, step {h / 2:.3g}·v ({halvings} halvings of "
               f"2^-7) over {int(keep.sum())} lanes ({int(jumps.sum())} with a jump or kink, "
               f"{int(nonfinite.sum())} with a non-finite AD derivative{left_out} left out); "
               f"tolerance 4|D(h)−D(h/2)| + 64u(Σ|S|/h + Σ|∂S|)", details)


class AtFixedInputs:
    """A :class:`Functional` of a value at fixed inputs: S_l = c_l Σ_channels value_l, where
    ``value()`` returns the Dr.Jit value (the phase function's eval_pdf value, a medium's
    coefficient, a BSDF's eval) and ``n`` its lanes; nothing is held."""

    fd_words = "the same sum"
    undefined_words = ""

    def __init__(self, value, c: np.ndarray, ad_words: str, what: str, owner: str,
                 max_halvings: int = MAX_HALVINGS, kinks: bool = True):
        self.value, self.c = value, c
        self.ad_words, self.what, self.owner = ad_words, what, owner
        self.max_halvings, self.kinks = max_halvings, kinks

    def _per_lane(self, x, finite_only: bool) -> np.ndarray:
        """c_l Σ_channels x_l (non-finite channels as 0 with ``finite_only``)."""
        a = probe.to_numpy(x, len(self.c))
        if finite_only:
            a = np.where(np.isfinite(a), a, 0.0)
        return self.c * (a if a.ndim == 1 else np.sum(a, axis=1))

    def lanes(self) -> np.ndarray:
        return self._per_lane(self.value(), True)

    def derivative(self) -> np.ndarray:
        out = self.value()
        dr.forward_to(out)
        return self._per_lane(dr.grad(out), False)

    def hold(self) -> None:
        return None

    def undefined(self, g) -> None:
        return None
