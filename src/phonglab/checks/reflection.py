r"""Check 2, ``reflection``: the reflection equation through the plugins' eval, sample and a render.

Quadrature (:func:`phonglab.physics.quadrature.albedo_by_quadrature`) of eval over the
hemisphere gives the albedo a(ω_i) = L_r under L_i = 1.  Exact expectations: lambert a = ρ at
every angle; phong a = k_d + k_s at normal incidence (∫ cos^p α cos θ dω = 2π/(p+2) when
R = N, times (p+2)/(2π)); and a ≤ 1 everywhere when k_d + k_s ≤ 1 (here k_d = k_s = 0.5,
sum 1).  Budget for these deterministic rows: 1e-5 absolute (float32 eval, ~2⁻²⁴ relative per
node, summed in float64) plus 3 |Q(20) − Q(40)|, the quadrature's own error estimate from two
node counts.  That estimate is ~1e-8 up to p = 1e4 but 4e-5 at p = 1e5, where float32
cos α = ω_o·R (spacing 2⁻²⁴ near 1) turns cos^p α into a staircase: p·2⁻²⁴ ≈ 0.6 % per node.

Monte Carlo: the mean of ``sample`` weights is an unbiased estimate of a(ω_i); rows per
exponent with the worst angle, tolerance z·SE.  Render: check_furnace_plane.xml shows
L_r = Le a(ω_r) at the camera direction.
"""

from __future__ import annotations

import math

import mitsuba as mi
import numpy as np

from .. import probe, registration
from ..physics.quadrature import albedo_by_quadrature, lobe_width
from ..verdict import Row
from .common import Config, Rows, gray, image_mean, phong_dict, render, worst

#: Exponents of the Phong albedo grid (0 and >= 1000 included).
EXPONENTS = (0.0, 1.0, 10.0, 100.0, 1000.0, 10000.0, 100000.0)
#: Incidence angles (degrees) of the albedo grid.
INCIDENCE = (0.0, 30.0, 60.0, 75.0, 85.0)
#: Absolute budget of a quadrature albedo (float32 eval summed in float64).
QTOL = 1e-5
#: The test materials: lambert ρ, phong k_d and k_s.
RHO, KD, KS = 0.7, 0.5, 0.5


def check_reflection(cfg: Config) -> list[Row]:
    """The reflection equation by quadrature, Monte Carlo and render (module docstring)."""
    registration.register()
    rows = Rows("reflection")
    cfg.note("reflection: lambert quadrature")
    lam = mi.load_dict(gray(cfg.lambert, reflectance=RHO))
    alb = [albedo_by_quadrature(lam, math.radians(t), 1.0) for t in INCIDENCE]
    rows.exact(f"{cfg.lambert}: quadrature", f"{cfg.lambert}: ∫ eval dω by quadrature, "
               f"θ_i 0..85°, worst", worst(alb, RHO), RHO, "Lambert: ∫ ρ/π cos θ dω = ρ", QTOL,
               per_angle=alb)

    pho = mi.load_dict(phong_dict(cfg.phong, KD, KS, EXPONENTS[0]))
    params = mi.traverse(pho)
    grid, qerrs = {}, {}
    for p in EXPONENTS:
        cfg.note(f"reflection: phong p={p:g}")
        _set_exponent(params, p)
        grid[p], qerrs[p] = _phong_exponent(cfg, rows, pho, p)
    allv = np.array([v for q in grid.values() for v in q])
    rows.exact(f"{cfg.phong}: albedo <= 1", f"{cfg.phong} k_d + k_s = 1: max albedo over "
               f"θ_i 0..85° × p 0..1e5", float(allv.max()), 1.0, "energy conservation",
               QTOL + 3 * max(qerrs.values()),
               relation="<=", grid={f"{p:g}": q for p, q in grid.items()})
    _furnace_plane_renders(cfg, rows, lam, pho, params)
    return rows.finish()


def _set_exponent(params, p: float) -> None:
    params["exponent"] = mi.Float(p)
    params.update()


def _phong_exponent(cfg: Config, rows: Rows, pho, p: float) -> tuple[list[float], float]:
    """The normal-incidence row and the sample() row of one exponent: (albedo per angle, qerr)."""
    width = lobe_width(p)
    quad = [albedo_by_quadrature(pho, math.radians(t), width) for t in INCIDENCE]
    # Error estimate of the quadrature (and of float32 eval, whose cos α near 1 is
    # quantized to 2⁻²⁴: a staircase at p = 1e5): |Q(20 nodes) − Q(40 nodes)| at θ_i = 0.
    qerr = abs(albedo_by_quadrature(pho, 0.0, width, n=40) - quad[0])
    rows.exact(f"{cfg.phong} p={p:g}: normal incidence",
               f"{cfg.phong} k_d={KD}, k_s={KS}, p={p:g}: quadrature albedo at θ_i = 0",
               quad[0], KD + KS, "(p+2)/(2π) normalization: k_d + k_s", QTOL + 3 * qerr,
               quadrature_error=qerr)
    # Monte Carlo from sample(): mean weight, per angle; report the worst z.
    n = max(1024, cfg.samples // len(INCIDENCE))
    rng = cfg.rng(200 + int(min(p, 1e6)))
    best = None
    for t, q in zip(INCIDENCE, quad):
        u = rng.random((n, 3))
        w = probe.sample(pho, probe.direction(math.radians(t)), u[:, 0], u[:, 1:]).weight[:, 0]
        mean, se = float(w.mean()), float(w.std(ddof=1) / math.sqrt(n))
        z = abs(mean - q) / se if se > 0 else (0.0 if mean == q else math.inf)
        if best is None or z > best[0]:
            best = (z, t, mean, q, se)
    _, t, mean, q, se = best
    rows.stat(f"{cfg.phong} p={p:g}: sample() vs quadrature",
              f"{cfg.phong} p={p:g}: mean sample() weight vs quadrature (worst of θ_i "
              f"0..85°, here {t:g}°)", mean, q, "reflection-equation quadrature of eval", se,
              tests=len(INCIDENCE), floor=QTOL + 3 * qerr, theta_deg=t, samples=n)
    return quad, qerr


def _furnace_plane_renders(cfg: Config, rows: Rows, lam, pho, params) -> None:
    """A plane under constant Le = 1 seen at θ_r: mean pixel = quadrature albedo a(ω_r)."""
    cfg.note("reflection: furnace plane renders")
    cases = [("lam", 0.0, 60.0), ("pho", 30.0, 0.0), ("pho", 30.0, 60.0), ("pho", 1000.0, 30.0)]
    for k, (mat, p, theta) in enumerate(cases):
        th = math.radians(theta)
        if mat == "lam":
            expected = albedo_by_quadrature(lam, th, 1.0)
            label = f"{cfg.lambert} ρ={RHO}"
        else:
            _set_exponent(params, p)
            expected = albedo_by_quadrature(pho, th, lobe_width(p))
            label = f"{cfg.phong} p={p:g}"
        d = 5.0
        res = render(cfg, "check_furnace_plane", 300 + k, material=mat, lambert=cfg.lambert,
                     phong=cfg.phong, rho=RHO, kd=KD, ks=KS, exponent=p,
                     ox=f"{d * math.sin(th):.9g}", oz=f"{d * math.cos(th):.9g}")
        mean, se, _ = image_mean(res)
        rows.stat(f"{label}: render θ_r={theta:g}°", f"{label}: plane under constant Le = 1, "
                  f"path tracer, mean pixel at θ_r = {theta:g}°", mean, expected,
                  "quadrature albedo a(ω_r) (reflection eq.)", se, floor=QTOL)
