r"""Check 4, ``constancy``: radiance constant along rays; irradiance 1/r²; mirror; dielectric L/n².

Scenes (each header derives its value): check_constancy_emitter.xml (Le at every distance,
zero variance: budget 8 ulp), check_furnace_plane.xml (a lambert plane under constant Le:
ρ Le at every distance), check_irradiancemeter.xml (E = π Le a²/r², r = 1, 10),
check_irradiance_probe.xml (r² L = 1 at r = 1..1000, a point source seen through a Lambertian
probe: the irradiancemeter has no emitter sampling and cannot reach r = 1000),
check_mirror.xml (Le), check_dielectric.xml (T Le/n² and T n² Le/(1 − F²), with
F = ((n − 1)/(n + 1))² at normal incidence and T = 1 − F).
"""

from __future__ import annotations

import math

import numpy as np

from ..verdict import Row
from .common import EPS32, Config, Rows, image_mean, render, worst

#: Camera-to-surface distances (scene units).
DISTANCES = (1.0, 10.0, 100.0, 1000.0)
#: Emitted radiance of every source.
LE = 1.0


def check_constancy(cfg: Config) -> list[Row]:
    """Radiance constancy, inverse square, mirror and dielectric (module docstring)."""
    rows = Rows("constancy")
    _emitter_at_distances(cfg, rows)
    _plane_at_distances(cfg, rows)
    _irradiancemeter(cfg, rows)
    _irradiance_probe(cfg, rows)
    cfg.note("constancy: mirror and dielectric")
    _mirror(cfg, rows)
    _dielectric(cfg, rows)
    return rows.finish()


def _emitter_at_distances(cfg: Config, rows: Rows) -> None:
    for k, d in enumerate(DISTANCES):
        cfg.note(f"constancy: distance {d:g}")
        res = render(cfg, "check_constancy_emitter", 500 + k, dist=f"{d:g}", passes=2, spp=16)
        rows.exact(f"emitter d={d:g}", f"emitting square seen from d = {d:g}: worst pixel",
                   worst(res.image[..., 0], LE), LE, "radiance is constant along a ray",
                   8 * EPS32 * LE, stderr=float(res.stderr[..., 0].max()))


def _plane_at_distances(cfg: Config, rows: Rows) -> None:
    rho = 0.7
    th = math.radians(60.0)
    for k, d in enumerate(DISTANCES):
        res = render(cfg, "check_furnace_plane", 510 + k, material="lam", lambert=cfg.lambert,
                     rho=rho, ox=f"{d * math.sin(th):.9g}", oz=f"{d * math.cos(th):.9g}")
        mean, se, _ = image_mean(res)
        rows.stat(f"{cfg.lambert} plane d={d:g}", f"{cfg.lambert} plane in constant Le = 1 seen "
                  f"from d = {d:g} at 60°: mean pixel", mean, rho * LE,
                  "ρ Le at every distance (constancy + reflection eq.)", se)


def _irradiancemeter(cfg: Config, rows: Rows) -> None:
    a = 0.5
    for k, r in enumerate((1.0, 10.0)):
        cfg.note(f"constancy: irradiancemeter r={r:g}")
        # A ray hits the source with probability (a/r)²: scale the samples with r².
        spp = 4096 * cfg.spp * int(max(1.0, r * r / 16))
        passes = 32
        res = render(cfg, "check_irradiancemeter", 520 + k, dist=f"{r:g}", radius=a, spp=spp,
                     passes=passes)
        mean, se, _ = image_mean(res)
        rows.stat(f"irradiancemeter r={r:g}", f"irradiancemeter E at r = {r:g} from a sphere "
                  f"a = {a} (× r² / (π Le a²))", mean * r * r / (math.pi * LE * a * a), 1.0,
                  "E = π Le a²/r² (inverse square)", se * r * r / (math.pi * LE * a * a),
                  dof=passes - 1,
                  E=mean, expected_E=math.pi * LE * a * a / r ** 2, spp=spp)


def _irradiance_probe(cfg: Config, rows: Rows) -> None:
    for k, r in enumerate(DISTANCES):
        res = render(cfg, "check_irradiance_probe", 530 + k, dist=f"{r:g}", passes=2, spp=16,
                     lambert=cfg.lambert)
        # Budget: E varies by 1.5 h²/r² <= 1.8e-7 over the visible patch (scene header), plus
        # float32 rounding (16 ulp).
        rows.exact(f"{cfg.lambert} probe r={r:g}", f"r² × radiance of a ρ=1 {cfg.lambert} probe "
                   f"lit by a point source at r = {r:g}: worst pixel",
                   worst(res.image[..., 0].astype(np.float64) * r * r, 1.0), 1.0,
                   "E = I/r², L = ρE/π, I = π", 1.8e-7 + 16 * EPS32,
                   stderr=float(res.stderr[..., 0].max()) * r * r)


def _mirror(cfg: Config, rows: Rows) -> None:
    res = render(cfg, "check_mirror", 540, passes=2, spp=16)
    rows.exact("perfect mirror", "emitter seen in a perfect mirror (conductor 'none'): worst "
               "pixel", worst(res.image[..., 0], LE), LE,
               "mirror keeps dA dω and F = 1: L = Le", 8 * EPS32 * LE,
               stderr=float(res.stderr[..., 0].max()))


def _dielectric(cfg: Config, rows: Rows) -> None:
    n = 1.5
    F = ((n - 1) / (n + 1)) ** 2
    T = 1 - F
    for k, (label, cam_z, em_z, expected, why) in enumerate((
            ("dielectric, glass → air", 5, 0, T * LE / n ** 2, "L/n² conserved: T Le / n²"),
            ("dielectric, air → glass", 0, 3, T * n * n * LE / (1 - F * F),
             "L/n² conserved: T n² Le/(1 − F²)"))):
        res = render(cfg, "check_dielectric", 550 + k, ior=n, cam_z=cam_z, em_z=em_z)
        mean, se, _ = image_mean(res)
        rows.stat(label, f"{label}: radiance through a smooth interface, n = {n}, normal "
                  f"incidence", mean, expected, why, se, without_eta2_scaling=expected * (
                      n * n if cam_z > 1 else 1 / (n * n)))
