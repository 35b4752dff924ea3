r"""Check 1, ``energy``: white furnace and the multi-bounce furnace, ``lambert`` next to ``diffuse``.

BSDF level, L_i = 1: the reflection-equation estimator with cosine-weighted directions
(pdf cos θ_o/π, Malley's method) is eval/pdf = (ρ/π cos θ_o)/(cos θ_o/π) = ρ for every
sample: zero variance, so every single sample must equal ρ to float32 precision (budget
16 ulp = 16·2⁻²⁴ ρ; the ratio of two float32 products rounds a few times).  The plugin's own
``sample`` weight too.

Renders: check_furnace_sphere.xml (a convex sphere in a constant environment: every pixel
ρ Le) with the path tracer (MIS of emitter and BSDF sampling: nonzero variance, statistical
row) and with `direct` using BSDF sampling only (zero variance, exact row);
check_furnace_enclosure.xml (camera inside a closed emitting enclosure: Le/(1 − ρ), or
Le (1 − ρ^D)/(1 − ρ) for path length D, the Neumann series).  Inside an emitting sphere
Mitsuba 3.9.1's sphere emitter biases MIS (:data:`SPHERE_BIAS_NOTE`); those rows are KNOWN.
"""

from __future__ import annotations

import math

import mitsuba as mi
import numpy as np

from .. import probe, registration
from ..verdict import Row
from .common import EPS32, Config, Rows, gray, image_mean, render, worst

SPHERE_BIAS_NOTE = (
    "Mitsuba 3.9.1 sphere emitter: sample_direction() treats a point on the sphere as inside "
    "(|p − c| <= r(1 + 1500 eps)) and samples by area, while pdf_direction() treats it as "
    "outside unless r/|p − c| >= 1 − eps and returns the cone pdf 1/(2π); the MIS weights then "
    "do not sum to 1 and the estimate is biased high. Each strategy alone is exact; a cube "
    "enclosure is unbiased. See docs/checks.md.")

#: Albedo of the furnace cases.
RHO = 0.7
#: Emitted radiance of the enclosures.
LE = 1.0
#: Path length of the ρ = 1 enclosures: L_D = D Le.
DEPTH = 5


def check_energy(cfg: Config) -> list[Row]:
    """White furnace and the multi-bounce furnace for ``lambert`` and the built-in ``diffuse``
    (the module docstring derives every expectation)."""
    registration.register()
    rows = Rows("energy")
    _bsdf_furnace(cfg, rows)
    _render_furnace(cfg, rows)
    _enclosures(cfg, rows)
    _one_bounce_in_sphere(cfg, rows)
    return rows.finish()


def _bsdf_furnace(cfg: Config, rows: Rows) -> None:
    """Every sample of eval/pdf_cos and of sample()'s weight equals ρ (θ_i 0..89°)."""
    thetas = np.radians([0.0, 30.0, 60.0, 80.0, 89.0])
    n = max(1024, cfg.samples // len(thetas))
    tol = 16 * EPS32 * RHO
    cfg.note("energy: BSDF level")
    for name in (cfg.lambert, "diffuse"):
        bsdf = mi.load_dict(gray(name, reflectance=RHO))
        rng = cfg.rng(1)
        wi = np.repeat(probe.direction(thetas), n, axis=0)
        u = rng.random((len(wi), 3))
        # Malley's method: cosine-weighted directions, pdf cos θ_o / π.
        wo = probe.to_numpy(mi.warp.square_to_cosine_hemisphere(
            mi.Point2f(mi.Float(u[:, 1].astype(np.float32)), mi.Float(u[:, 2].astype(np.float32)))))
        pdf = wo[:, 2] / math.pi
        est = probe.eval(bsdf, wi, wo)[:, 0] / pdf
        per_angle = est.reshape(len(thetas), n).mean(axis=1)
        rows.exact(f"{name}: furnace, eval/cos-pdf", f"{name}: every sample of eval/pdf_cos "
                   f"(L_i = 1, θ_i 0..89°), worst", worst(est, RHO), RHO,
                   "ρ/π·cos / (cos/π) = ρ: zero variance",
                   tol, stderr=float(est.std() / math.sqrt(est.size)),
                   mean_per_angle=per_angle.tolist(), sample_std=float(est.std()))
        w = probe.sample(bsdf, wi, u[:, 0], u[:, 1:]).weight[:, 0]
        rows.exact(f"{name}: furnace, sample weight", f"{name}: every sample() weight "
                   f"(θ_i 0..89°), worst", worst(w, RHO), RHO, "eval/pdf = ρ (cosine sampling)",
                   tol, stderr=float(w.std() / math.sqrt(w.size)), sample_std=float(w.std()))


def _render_furnace(cfg: Config, rows: Rows) -> None:
    """A sphere in a constant environment: path tracer (MIS) and `direct` with BSDF sampling."""
    cfg.note("energy: furnace sphere")
    for k, name in enumerate((cfg.lambert, "diffuse")):
        res = render(cfg, "check_furnace_sphere", 10 + k, bsdf=name, rho=RHO)
        mean, se, px_se = image_mean(res)
        rows.stat(f"{name}: furnace render, path (MIS)", f"{name}: sphere in constant Le = 1, "
                  f"path tracer, mean pixel", mean, RHO, "convex: L = ρ Le (reflection eq.)", se,
                  pixel_stderr=px_se, nonzero_variance=bool(px_se > 0))
        direct = mi.load_dict({"type": "direct", "emitter_samples": 0, "bsdf_samples": 1})
        res = render(cfg, "check_furnace_sphere", 20 + k, integrator=direct, bsdf=name, rho=RHO,
                     passes=2)
        rows.exact(f"{name}: furnace render, BSDF only", f"{name}: same, `direct` with BSDF "
                   f"sampling only, worst pixel", worst(res.image[..., 0], RHO), RHO,
                   "weight ρ per sample: zero variance", 16 * EPS32 * RHO,
                   stderr=float(res.stderr[..., 0].max()))


def _enclosures(cfg: Config, rows: Rows) -> None:
    """Inside closed emitting enclosures: cube ρ = 0.5, sphere and cube ρ = 1 at depth D."""
    cfg.note("energy: closed enclosures")
    for k, name in enumerate((cfg.lambert, "diffuse")):
        r = 0.5
        d = 40
        res = render(cfg, "check_furnace_enclosure", 30 + k, shape="cube", bsdf=name, rho=r,
                     le=LE, max_depth=d)
        mean, se, _ = image_mean(res)
        # Le (1 − ρ^D)/(1 − ρ): ρ^40 = 9e-13, i.e. Le/(1 − ρ) to float precision.
        rows.stat(f"{name}: cube enclosure ρ=0.5", f"{name}: inside an emitting closed cube, "
                  f"path (MIS), max_depth {d}", mean, LE * (1 - r ** d) / (1 - r),
                  "L = Le/(1 − ρ) (Neumann series)", se)
    for k, name in enumerate((cfg.lambert, "diffuse")):
        res = render(cfg, "check_furnace_enclosure", 40 + k, shape="sphere", bsdf=name, rho=1.0,
                     le=LE, max_depth=DEPTH)
        mean, se, _ = image_mean(res)
        rows.stat(f"{name}: sphere enclosure ρ=1 D=5", f"{name}: inside an emitting sphere, "
                  f"path (MIS), max_depth 5", mean, DEPTH * LE,
                  "L_D = Le (1 − ρ^D)/(1 − ρ) → D Le at ρ = 1", se, known_issue=SPHERE_BIAS_NOTE,
                  bias_per_bounce=(mean - DEPTH * LE) / (DEPTH - 1))
    res = render(cfg, "check_furnace_enclosure", 50, shape="cube", bsdf=cfg.lambert, rho=1.0,
                 le=LE, max_depth=DEPTH)
    mean, se, _ = image_mean(res)
    rows.stat(f"{cfg.lambert}: cube enclosure ρ=1 D=5", f"{cfg.lambert}: same in a cube "
              f"(no sphere emitter)", mean, DEPTH * LE, "L_D = D Le at ρ = 1", se)


def _one_bounce_in_sphere(cfg: Config, rows: Rows) -> None:
    """Inside the emitting sphere, `direct` with each strategy alone: exact per sample."""
    mismatch = _sphere_pdf_mismatch(cfg)
    for k, (label, em, bs) in enumerate((("emitter only", 1, 0), ("BSDF only", 0, 1))):
        direct = mi.load_dict({"type": "direct", "emitter_samples": em, "bsdf_samples": bs})
        res = render(cfg, "check_furnace_enclosure", 60 + k, integrator=direct, passes=2,
                     shape="sphere", bsdf=cfg.lambert, rho=1.0, le=LE)
        # Emitter sampling inside a sphere: cos θ cos θ' / d² = 1/(4R²) on every chord, so the
        # area-sampled estimate Le ρ/π · 4πR² · cos cos'/d² = ρ Le exactly: zero variance too.
        rows.exact(f"{cfg.lambert}: sphere, {label}", f"{cfg.lambert}: inside the sphere, "
                   f"`direct` {label}, worst pixel", worst(res.image[..., 0], 2 * LE), 2 * LE,
                   "one bounce: Le + ρ Le, exact per sample", 64 * EPS32 * 2 * LE,
                   stderr=float(res.stderr[..., 0].max()),
                   sphere_pdf_mismatch_fraction=mismatch)


def _sphere_pdf_mismatch(cfg: Config) -> float:
    """Fraction of points on an emitting sphere (hit from inside) where the emitter's
    pdf_direction() disagrees (> 0.1 %) with the pdf its sample_direction() returned."""
    scene = mi.load_dict({"type": "scene", "s": {
        "type": "sphere", "flip_normals": True, "bsdf": {"type": "diffuse"},
        "emitter": {"type": "area", "radiance": {"type": "rgb", "value": 1.0}}}})
    rng = cfg.rng(99)
    n = 1 << 14
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    si = scene.ray_intersect(mi.Ray3f(mi.Point3f(0.0, 0.0, 0.0), probe.to_vectors(d)))
    u = rng.random((n, 2)).astype(np.float32)
    em = scene.emitters()[0]
    ds, _ = em.sample_direction(si, mi.Point2f(mi.Float(u[:, 0]), mi.Float(u[:, 1])))
    a, b = probe.to_numpy(ds.pdf), probe.to_numpy(em.pdf_direction(si, ds))
    return float(np.mean(np.abs(a - b) > 1e-3 * np.abs(a)))
