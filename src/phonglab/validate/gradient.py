r"""The AD-against-finite-difference verdict of a sampled quantity, for any kind: Dr.Jit's
derivative of Σ c·weight of a ``source``'s ``sample_direction`` against a central difference
with the samples held.  The emitter kind's ``gradient`` topic
(:mod:`phonglab.validate.emitter.gradient`) uses it on an emitter, the phase-function kind's
(:mod:`phonglab.validate.phase.gradient`) on eval_pdf at fixed directions presented as such a
sample.  :func:`verdict` is one parameter's row; ``setup.emitter`` is the source.

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

As in :mod:`phonglab.validate.bsdf.gradient` (the same derivation): the direction v_i = |x_i|
(max |x| or 0.1 where x_i = 0); AD forward mode (``dr.forward_to``); FD
D(h) = (S(x + hv) − S(x − hv))/2h and D(h/2).  h starts at 2⁻⁷ and is halved (at most 16
times) until the sums Σ D(h) and Σ D(h/2) agree to 1 % + the round-off bound and at least
half of the lanes converge (a peaked lobe's curvature: hg at g = 0.8 needs a smaller step on
the lanes near forward scattering): a spectral
variant's ``radiance.value`` holds the polynomial coefficients of Mitsuba's RGB-to-spectrum
model, the first multiplying λ² ≈ 2.5·10⁵, and a step of 2⁻⁷ · 0.1 drives its sigmoid into
saturation, where the quotients measure nothing (the step is chosen from the quotients alone,
never from AD).  Lanes whose quotients do not converge (|D_l(h) − D_l(h/2)| > 1 % + 4× the
round-off bound: a jump moving with x), or whose one-sided quotients at h/2 disagree
(|D⁺_l − D⁻_l| > 1 % + 8× the bound: a kink within h/2 of x, e.g. a spot lane just outside
its cutoff, lit for a larger cutoff_angle only, whose central quotient is half the one-sided
slope at any step while AD gives the left one, 0) are left out and counted.  Tolerance on the
kept sums: 4|D(h) − D(h/2)| + 64u(Σ|S_l|/h + Σ|∂S_l|).  Lanes along which no radiance arrives
at x (e₀ = 0: an emitter swept to an emitted quantity of 0) while the weight's derivative is not
0 have no sampling factor (0/0) and are left out too; where they are most lanes the row is
skipped, saying so.  x is written as an opaque value so
the kernels compile once, and restored after each parameter.
"""

from __future__ import annotations

import drjit as dr
import numpy as np

from .. import probe
from ..verdict import Row
from .roundoff import EPS32

ROUND_OFF = 64 * EPS32
#: The first finite-difference step (relative, along v), and how often it may be halved.
H0 = 2.0 ** -7
MAX_HALVINGS = 16


def _lanes(setup, it, fixed, c) -> np.ndarray:
    """Per lane: c · Σ_channels w₀ · eval_direction(ds₀) / e₀ at the fixed samples ds₀ (the
    weight with its sampling factor w₀/e₀ held; 0 where e₀ = 0)."""
    ds, ratio = fixed
    x = probe.to_numpy(setup.calls.eval_direction(it, ds), len(c)) * ratio
    return c * np.sum(np.where(np.isfinite(x), x, 0.0), axis=1)


def _fixed(setup, it, u, n: int):
    """ds₀ = sample_direction at the current parameters (evaluated, no gradient) and the
    sampling factor w₀/e₀ per channel, e₀ = eval_direction(ds₀)."""
    ds, w = setup.calls.sample_direction(it, u)
    ds = dr.detach(ds)
    dr.eval(ds)
    w0 = probe.to_numpy(w, n)
    e0 = probe.to_numpy(setup.calls.eval_direction(it, ds), n)
    return ds, np.where((e0 != 0) & np.isfinite(w0), w0 / np.where(e0 != 0, e0, 1.0), 0.0)


def _dark(setup, it, u, n: int) -> np.ndarray:
    """Per lane: no radiance arrives along the sample at x (e₀ = 0 in every channel), so the
    sampling factor w₀/e₀ the FD side holds is undefined there (an emitter whose emitted
    quantity is 0 at the point swept: its FD side is 0 whatever the derivative)."""
    ds, _ = setup.calls.sample_direction(it, u)
    e0 = probe.to_numpy(setup.calls.eval_direction(it, dr.detach(ds)), n)
    return np.all(e0 == 0, axis=1)


def _set(params, key, value):
    value = type(value)(value)
    dr.make_opaque(value)
    params[key] = value
    params.update()


def _ad(setup, params, key, v, it, u, c) -> np.ndarray:
    """Per lane: the forward-mode derivative of c·Σ weight along v."""
    x = params[key]
    dr.enable_grad(x)
    params.update()
    try:
        dr.set_grad(x, v)
        _, w = setup.calls.sample_direction(it, u)
        dr.forward_to(w)
        return c * np.sum(probe.to_numpy(dr.grad(w), len(c)), axis=1)
    finally:                 # a parameter left tracked would add its derivative to the next's
        dr.disable_grad(x)
        params.update()


def _quotients(setup, params, key, x0, v, h, it, fixed, c, s0):
    """(D(h), D(h/2), D⁺(h/2), D⁻(h/2)) per lane; x is restored to x0."""
    fd = []
    for step in (h, h / 2):
        s = []
        for k in (1.0, -1.0):
            _set(params, key, x0 + (k * step) * v)
            s.append(_lanes(setup, it, fixed, c))
        fd.append((s[0] - s[1]) / (2.0 * step))
    _set(params, key, x0)
    return fd[0], fd[1], (s[0] - s0) / (h / 2), (s0 - s[1]) / (h / 2)


def _refused(key, h, exc, word: str) -> Row:
    if "does not depend on the input" in str(exc):
        return Row("gradient", key, None, None, None, None, "skipped",
                   "sample_direction's weight does not depend on this parameter (Dr.Jit: the "
                   "output does not depend on it; e.g. a spot's texture when none is given)", {})
    return Row("gradient", key, None, None, None, None, "skipped",
               f"the validator's own finite-difference step x ± {h:g}·v left the values the "
               f"{word} accepts (it raised: "
               f"{(str(exc).splitlines() or [type(exc).__name__])[0][:160]}): a limit of the "
               f"check's step, not a defect of the {word}", {})


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
    against 3.4: ValidatorIssue ``gradient-convergence-judged-by-ad``.)  Lanes with a
    non-finite quotient or AD derivative are the caller's to count."""
    scale = 0.01 * np.abs(d2)
    with np.errstate(invalid="ignore"):
        out = np.abs(d1 - d2) > scale + 4.0 * noise
        if forward is not None:
            out |= np.abs(forward - backward) > scale + 8.0 * noise
    return out


def verdict(setup, params, key, it, u, c, word: str) -> Row:
    """One parameter's gradient row: forward-mode AD of Σ c·weight along v against the
    central differences with the samples held (module docstring); ``word``: what the plugin
    is, for a row's reason."""
    x0 = params[key]
    if not dr.is_diff_v(x0) or dr.type_v(x0) not in (dr.VarType.Float32, dr.VarType.Float64):
        return Row("gradient", key, None, None, None, None, "skipped",
                   f"{type(x0).__name__} is not a differentiable floating-point value", {})
    x0 = type(x0)(x0)
    values = np.array(x0).ravel() if dr.width(x0) else np.zeros(1)
    fill = max(float(np.max(np.abs(values))), 0.1)
    v = dr.detach(dr.select(x0 != 0, dr.abs(x0), fill))
    h = H0
    try:
        g = _ad(setup, params, key, v, it, u, c)
        fixed = _fixed(setup, it, u, len(c))
        dark = _dark(setup, it, u, len(c))
        s0 = _lanes(setup, it, fixed, c)
        s_abs = np.abs(s0)
        for halvings in range(MAX_HALVINGS + 1):
            h = H0 * 2.0 ** -halvings
            d1, d2, forward, backward = _quotients(setup, params, key, x0, v, h, it, fixed, c,
                                                   s0)
            noise = ROUND_OFF * (s_abs / (h / 2) + np.abs(g))
            jumps = unconverged(d1, d2, noise, forward, backward) & np.isfinite(g)
            if (abs(np.nansum(d1) - np.nansum(d2)) <= 0.01 * abs(np.nansum(d2)) + noise.sum()
                    and jumps.sum() <= len(g) // 2):
                break
    except Exception as exc:
        _set(params, key, x0)
        return _refused(key, h, exc, word)
    nonfinite = ~np.isfinite(g)
    # no radiance arrives, yet the weight moves with x: the FD side's factor w₀/e₀ is 0/0
    undefined = dark & (g != 0) & ~nonfinite
    keep = ~jumps & ~nonfinite & ~undefined & np.isfinite(d1) & np.isfinite(d2)
    ad, f1, f2 = float(g[keep].sum()), float(d1[keep].sum()), float(d2[keep].sum())
    details = {"fd_h": f1, "fd_h2": f2, "h": h / 2, "halvings": halvings, "lanes": len(g),
               "jump_lanes": int(jumps.sum()), "nonfinite_ad_lanes": int(nonfinite.sum())}
    left_out = ""
    if undefined.any():
        details["undefined_factor_lanes"] = int(undefined.sum())
        left_out = f", {int(undefined.sum())} with no arriving radiance"
    if keep.sum() < len(g) // 2 and undefined.sum() > jumps.sum():
        return Row("gradient", key, ad, f2, None, None, "skipped",
                   f"no radiance arrives along {int(undefined.sum())} of {len(g)} samples at "
                   f"this point (the emitted quantity is 0) while the weight's derivative is "
                   f"not 0: the difference side's sampling factor w₀/e₀ is 0/0 there, nothing "
                   f"to compare", details)
    if keep.sum() < len(g) // 2:
        return Row("gradient", key, ad, f2, None, None, "skipped",
                   f"the difference quotients do not converge on {int(jumps.sum())} of {len(g)} "
                   f"lanes: nothing to compare", details)
    tol = 4.0 * abs(f1 - f2) + float(noise[keep].sum())
    ok = np.isfinite(ad) and abs(ad - f2) <= tol
    return Row("gradient", key, ad, f2, abs(f1 - f2) / 3.0, tol, "pass" if ok else "fail",
               f"forward-mode AD of Σ c·(sample_direction weight) along v (v_i = |x_i|) vs the "
               f"central difference of Σ c·w₀·eval_direction(ds₀)/e₀ (samples held), step "
               f"{h / 2:.3g}·v ({halvings} halvings of 2^-7) over "
               f"{int(keep.sum())} lanes ({int(jumps.sum())} with a jump or kink, "
               f"{int(nonfinite.sum())} with a non-finite AD derivative{left_out} left out); "
               f"tolerance "
               f"4|D(h)−D(h/2)| + 64u(Σ|S|/h + Σ|∂S|)", details)
