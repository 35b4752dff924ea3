r"""The ``gradient`` topic: an AD integrator's forward derivative of the mean image with
respect to a BSDF reflectance, against a central finite difference with the same seed.

Scene: the closed enclosure (:func:`phonglab.validate.integrator.scenes.enclosure`, ρ = 0.5) at
max_depth 3 (below ``rr_depth``: no Russian roulette, whose decisions would move with ρ), or at
the integrator's fixed depth; for an integrator of unknown depth the plane under the point
light.  Parameter: the walls' ``reflectance`` x (gray, moved along (1, 1, 1)).  In pass k:
AD = the mean of dr.grad of ``mi.render(scene, params, seed=s_k, seed_grad=g_k)`` after
``dr.forward(x)`` (Mitsuba refuses g_k = s_k: "the primal and differential seed should be
different to ensure unbiased gradient computation", so the derivative's samples are
independent of the primal's); FD(h) = (M(x + h) − M(x − h))/2h of primal renders M with one
seed s_k on both sides, h = 0.05 and h/2.  With one seed every sample of M is a polynomial in
x of degree D − 1 (the walls' albedo to the power of the bounce count), so FD(h) is an unbiased
estimate of the derivative up to the truncation |FD(h) − FD(h/2)|, and both estimate
dL_D/dρ = Le Σ_{k<D} k ρ^{k−1} (2 at D = 3).  The row fails when
|mean_k (AD_k − FD_k)| > t_{P−1} · stderr + 4 mean_k|FD_k(h) − FD_k(h/2)| + 64u (M/h + |AD|),
stderr the spread of the P differences.  Non-AD integrators (Python ``SamplingIntegrator``
plugins, Mitsuba's C++ integrators) and non-AD variants are skipped.
"""

from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi
import numpy as np

from ...verdict import NOT_APPLICABLE
from ... import stats
from ..roundoff import EPS32
from . import scenes
from .config import seed
from .setup import Target, radiance_channels
from .topics import Row

#: The finite-difference step on the reflectance.
H = 0.05
RHO = 0.5
DEPTH = 3


def applies(target: Target) -> str:
    """"" when the topic applies, else why it is skipped."""
    if not dr.is_diff_v(mi.Float):
        return f"{mi.variant()} is not an AD variant"
    if not target.ad:
        return ("not an AD integrator (mi.ad.integrators.common.ADIntegrator): mi.render "
                "cannot differentiate it")
    if target.aov:
        return "an AOV integrator returns channels that are not radiance"
    return ""


def _setup(target: Target, res: int):
    if target.depth == "settable" or (target.own_depth or 0) >= 2:
        depth = DEPTH if target.depth == "settable" else target.own_depth
        integ = target.make(depth, whole=True)
        deriv = sum(k * RHO ** (k - 1) for k in range(1, depth)) * scenes.LE
        return (scenes.enclosure(res, RHO), "enclosure.bsdf.reflectance.value", integ,
                f"enclosure ρ = {RHO} D = {depth}", deriv)
    return (scenes.plane(res, RHO), "plane.bsdf.reflectance.value", target.integrator,
            "plane under a point light", scenes.plane_value(RHO) / RHO)


def _mean(img) -> float:
    """The mean of the image's radiance channels (AOV channels, if any, follow them)."""
    return float(np.asarray(img, np.float64)[..., :radiance_channels()].mean())


def gradient(target: Target, opts, m: int) -> list[Row]:
    why = applies(target)
    if why:
        return [Row("gradient", "d mean / d reflectance: AD against FD", None, None, None,
                    None, "skipped", why, {NOT_APPLICABLE: True})]
    scene_dict, key, integ, label, analytic = _setup(target, opts.res)
    scene = mi.load_dict(scene_dict)
    params = mi.traverse(scene)
    x0 = mi.Color3f(params[key])
    spp = opts.gradient_spp
    ad, fd, fd2, prim = [], [], [], []

    def primal(x, s):
        params[key] = mi.Color3f(x)
        params.update()
        return _mean(mi.render(scene, params, spp=spp, seed=s, integrator=integ))

    mode = ["forward"]

    def derivative(s) -> float:
        """d mean / dt along x0 + t (1, 1, 1): forward mode, or reverse mode (the gradient's
        components summed) for an integrator that implements only that one (prbvolpath
        raises on forward mode, src/python/python/ad/integrators/prbvolpath.py:108-110)."""
        params[key] = mi.Color3f(x0)
        dr.enable_grad(params[key])
        params.update()
        try:
            if mode[0] == "forward":
                img = mi.render(scene, params, spp=spp, seed=s, seed_grad=s + 7919,
                                integrator=integ)
                dr.forward(params[key])
                return _mean(dr.grad(img))
            img = mi.render(scene, params, spp=spp, seed=s, seed_grad=s + 7919,
                            integrator=integ)
            dr.backward(dr.mean(img, axis=None))
            return float(np.sum(np.asarray(dr.grad(params[key]), np.float64)))
        finally:
            dr.disable_grad(params[key])

    for k in range(opts.gradient_passes):
        s = seed(opts.seed, "gradient", k) + 1
        try:
            ad.append(derivative(s))
        except RuntimeError as exc:
            chain = f"{exc} {exc.__cause__ or ''}"
            if mode[0] != "forward" or "forward-mode" not in chain:
                raise
            mode[0] = "reverse"
            ad.append(derivative(s))
        x = RHO
        fd.append((primal(x + H, s) - primal(x - H, s)) / (2 * H))
        fd2.append((primal(x + H / 2, s) - primal(x - H / 2, s)) / H)
        prim.append(primal(x, s))
    params[key] = x0
    params.update()
    ad, fd, fd2 = np.array(ad), np.array(fd), np.array(fd2)
    d = ad - fd
    p = len(d)
    se = float(d.std(ddof=1) / math.sqrt(p))
    t = stats.t_critical(p - 1, stats.ALPHA, m)
    trunc = 4.0 * float(np.mean(np.abs(fd - fd2)))
    round_off = 64 * EPS32 * (float(np.mean(prim)) / H + float(np.mean(np.abs(ad))))
    tol = t * se + trunc + round_off
    ok = bool(np.all(np.isfinite(ad)) and abs(d.mean()) <= tol)
    return [Row("gradient", f"d mean / d reflectance: AD against FD ({label})",
                float(ad.mean()), float(fd.mean()), se, tol, "pass" if ok else "fail",
                f"{mode[0]} AD against central differences h = {H} (one seed on both "
                f"sides), {p} passes × {spp} spp; t_{p - 1} = {t:.2f} (Šidák, m = {m}) × "
                f"stderr of the differences + truncation {trunc:.2g} + round-off {round_off:.2g}",
                {"ad": ad.tolist(), "fd": fd.tolist(), "fd_half_step": fd2.tolist(),
                 "analytic": analytic, "parameter": key, "ad_mode": mode[0]})]
