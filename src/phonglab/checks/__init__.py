r"""The comparator: physics checks of phonglab's plugins and of Mitsuba's built-ins, side by side.

Each ``check_<name>(cfg)`` returns a list of :class:`CheckResult` rows: what is compared, the
measured value, the expected value and where the expectation comes from, the Monte Carlo
standard error, the tolerance and the verdict.  :func:`run_checks` runs several of them;
``phonglab check`` prints the rows as a table (:mod:`phonglab.cmd_check`).

The six checks (docs/checks.md has the table of a real run):

``energy``      white furnace: ρ at the BSDF level (zero variance), in a path-traced furnace
                (MIS: nonzero variance), and L = Le/(1 − ρ) inside a closed emitting enclosure.
``reflection``  the reflection equation L_r(ω_r) = ∫ f_r(ω_i, ω_r) L_i cos θ_i dω_i by
                deterministic quadrature of the plugins' ``eval``, against Monte Carlo from their
                ``sample`` and against a render; Phong albedo = k_d + k_s at normal incidence, ≤ 1.
``scene``       a whole Cornell box rendered with ``lambert`` and with ``diffuse``: per-pixel
                Welch t tests (Holm correction) and the mean difference within its error.
``constancy``   radiance constant along rays (distances 1..1000), irradiance falling as 1/r²,
                radiance kept by a mirror and L/n² kept across a dielectric interface.
``snell``       refraction directions (seed formula, ``mi.refract``, built-in ``dielectric``),
                n₁ sin θ₁ = n₂ sin θ₂, total internal reflection, R + T = 1.
``sanity``      reciprocity, non-negativity and finiteness, weight = eval/pdf, χ² sampling test.

Statistics: every statistical row has an analytic expectation μ and an estimate x with
standard error s (sample standard deviation / √n, or the per-pixel errors of independent
render passes); it passes when |x − μ| ≤ z s, with z the two-sided normal quantile at the
per-row level 1 − (1 − α)^(1/m): α = ALPHA = 0.01 and a Šidák correction over the m
statistical tests of that check [Šidák 1967].  Deterministic rows compare against a
float32 rounding budget stated where they are built.  Seeds are fixed (``Config.seed``), so
a run is reproducible.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

#: Family-wise significance level of each check's statistical rows (Šidák over its rows).
ALPHA = 0.01
#: float32 unit roundoff 2^-24.
EPS32 = 2.0 ** -24

#: Names accepted by ``--only``, in the order the table lists them.
CHECK_NAMES = ("energy", "reflection", "scene", "constancy", "snell", "sanity")


# --------------------------------------------------------------------------------------------
# Records
# --------------------------------------------------------------------------------------------

@dataclass
class CheckResult:
    """One row of the table.

    ``relation`` says how measured and expected are compared: ``"=="`` passes when
    |measured − expected| ≤ tolerance, ``"<="`` when measured ≤ expected + tolerance,
    ``">="`` when measured ≥ expected − tolerance.  A row with a ``known_issue`` that does
    not pass is reported as KNOWN (a documented discrepancy outside phonglab, with its
    measured size) and does not fail the run.
    """

    check: str                   #: the check it belongs to (energy, reflection, ...)
    name: str                    #: short row id, unique within the check
    compared: str                #: what is compared, in words
    measured: float
    expected: float
    source: str                  #: where the expectation comes from
    stderr: float                #: Monte Carlo standard error of measured (0: deterministic)
    tolerance: float
    passed: bool
    relation: str = "=="
    known_issue: str | None = None
    details: dict[str, Any] = field(default_factory=dict)

    @property
    def status(self) -> str:
        if self.passed:
            return "pass"
        return "KNOWN" if self.known_issue else "FAIL"

    @property
    def ok(self) -> bool:
        """True unless this row should make ``phonglab check`` fail."""
        return self.passed or self.known_issue is not None

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["status"] = self.status
        return _jsonable(d)


def _jsonable(x):
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, (np.floating, float)):
        x = float(x)
        return x if math.isfinite(x) else str(x)
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (np.bool_,)):
        return bool(x)
    if isinstance(x, Path):
        return str(x)
    return x


def sidak(alpha: float, m: int) -> float:
    """Per-test level keeping the family-wise error rate at alpha over m independent tests."""
    return 1.0 - (1.0 - alpha) ** (1.0 / max(1, m))


def z_critical(alpha: float, m: int) -> float:
    """Two-sided normal quantile for the Šidák-corrected level of m tests."""
    from scipy.stats import norm

    return float(norm.isf(sidak(alpha, m) / 2.0))


class _Rows:
    """Collects a check's rows; statistical rows get their tolerance z·s once m is known."""

    def __init__(self, check: str):
        self.check = check
        self.rows: list[CheckResult] = []
        self._stat: list[tuple[CheckResult, int, float]] = []

    def exact(self, name, compared, measured, expected, source, tolerance, *, relation="==",
              stderr=0.0, extra_ok=True, known_issue=None, **details) -> CheckResult:
        """A deterministic row: passes on the float budget ``tolerance`` (and ``extra_ok``)."""
        row = CheckResult(self.check, name, compared, float(measured), float(expected), source,
                          float(stderr), float(tolerance),
                          bool(_compare(measured, expected, tolerance, relation) and extra_ok),
                          relation, known_issue, details)
        self.rows.append(row)
        return row

    def stat(self, name, compared, measured, expected, source, stderr, *, tests=1,
             floor=0.0, dof=None, known_issue=None, **details) -> CheckResult:
        """A statistical row: |measured − expected| ≤ z·stderr (+ floor, a stated float budget).

        ``tests`` counts the independent tests the row stands for (e.g. the worst of 3 channels).
        ``dof``: degrees of freedom of a standard error estimated from few independent passes
        (Student t quantile instead of the normal one); None when it pools many pixels.
        """
        row = CheckResult(self.check, name, compared, float(measured), float(expected), source,
                          float(stderr), math.nan, False, "==", known_issue, details)
        self.rows.append(row)
        self._stat.append((row, tests, floor, dof))
        return row

    def finish(self) -> list[CheckResult]:
        from scipy.stats import t as student_t

        m = sum(t for _, t, _, _ in self._stat)
        if m:
            # The worst of t tests at level a' passes at level 1 − (1 − a')^t: count all of them.
            level = sidak(ALPHA, m)
            for row, _, floor, dof in self._stat:
                z = z_critical(ALPHA, m) if dof is None else float(student_t.isf(level / 2, dof))
                row.tolerance = z * row.stderr + floor
                row.passed = bool(np.isfinite(row.measured)
                                  and abs(row.measured - row.expected) <= row.tolerance)
                row.details.setdefault("z", round(z, 3))
                if row.stderr > 0:
                    row.details.setdefault("z_score", (row.measured - row.expected) / row.stderr)
        return self.rows


def _compare(measured, expected, tol, relation) -> bool:
    measured, expected, tol = float(measured), float(expected), float(tol)
    if not (math.isfinite(measured) and math.isfinite(expected)):
        return False
    if relation == "==":
        return abs(measured - expected) <= tol
    if relation == "<=":
        return measured <= expected + tol
    if relation == ">=":
        return measured >= expected - tol
    raise ValueError(f"unknown relation {relation!r}")


# --------------------------------------------------------------------------------------------
# Configuration
# --------------------------------------------------------------------------------------------

@dataclass
class Config:
    """How hard the checks work.

    ``spp`` is the samples per pixel of every statistical render; BSDF-level Monte Carlo
    estimates use ``samples`` directions per case (default 1024·spp) and the χ² tests
    ``chi2_samples`` (default 4096·spp).  ``lambert``/``phong`` name the plugins under test
    (the tests register deliberately broken variants under other names).
    """

    spp: int = 256
    seed: int = 0
    samples: int | None = None
    chi2_samples: int | None = None
    passes: int = 8
    out_dir: Path = Path("out/checks")
    lambert: str = "lambert"
    phong: str = "phong"
    progress: Callable[[str], None] | None = None

    def __post_init__(self):
        from ..errors import PhonglabError

        if int(self.spp) < 8:
            raise PhonglabError(f"--spp must be at least 8 (the renders are split into passes "
                                f"for their standard errors), got {self.spp}.")
        self.spp = int(self.spp)
        if self.samples is None:
            self.samples = 1024 * self.spp
        if self.chi2_samples is None:
            self.chi2_samples = 4096 * self.spp
        self.out_dir = Path(self.out_dir)

    @classmethod
    def small(cls, **kw) -> "Config":
        """The test suite's settings: same checks, fewer samples."""
        kw.setdefault("spp", 16)
        return cls(**kw)

    def note(self, msg: str) -> None:
        if self.progress is not None:
            self.progress(msg)


# --------------------------------------------------------------------------------------------
# Dr.Jit helpers (vectorized over many directions in one kernel)
# --------------------------------------------------------------------------------------------

def _mi():
    import mitsuba as mi

    from .. import registration

    registration.register()
    return mi


def _vec(a: np.ndarray):
    mi = _mi()
    a = np.asarray(a, dtype=np.float32)
    return mi.Vector3f(*(mi.Float(np.ascontiguousarray(a[:, k])) for k in range(3)))


def _arr(x) -> np.ndarray:
    """A Dr.Jit value as float64 numpy: Vector3f/Color3f -> (n, 3), Float -> (n,)."""
    a = np.array(x, dtype=np.float64)
    return a.T if a.ndim == 2 else a


def _ch0(x) -> np.ndarray:
    a = _arr(x)
    return a[:, 0] if a.ndim == 2 else a


def _si(wi: np.ndarray):
    import drjit as dr

    mi = _mi()
    si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
    si.wi = _vec(wi)
    si.uv = mi.Point2f(0.5, 0.5)
    si.n = mi.Normal3f(0.0, 0.0, 1.0)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0.0, 0.0, 1.0))
    return si


def _dir(theta) -> np.ndarray:
    """Unit vectors (sin θ, 0, cos θ) in the local frame, θ in radians."""
    theta = np.atleast_1d(np.asarray(theta, dtype=np.float64))
    return np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=-1)


def bsdf_eval(bsdf, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """Channel 0 of ``bsdf.eval`` (= f_r cos θ_o) for pairs of local directions."""
    mi = _mi()
    return _ch0(bsdf.eval(mi.BSDFContext(), _si(wi), _vec(wo)))


def bsdf_pdf(bsdf, wi, wo) -> np.ndarray:
    mi = _mi()
    return _ch0(bsdf.pdf(mi.BSDFContext(), _si(wi), _vec(wo)))


def bsdf_sample(bsdf, wi: np.ndarray, u: np.ndarray):
    """``bsdf.sample`` with uniform numbers u (n, 3): (wo (n,3), pdf, weight channel 0)."""
    mi = _mi()
    u = np.asarray(u, dtype=np.float32)
    bs, weight = bsdf.sample(mi.BSDFContext(), _si(wi), mi.Float(u[:, 0]),
                             mi.Point2f(mi.Float(u[:, 1]), mi.Float(u[:, 2])))
    return _arr(bs.wo), _ch0(bs.pdf), _ch0(weight)


def _rng(cfg: Config, stream: int) -> np.random.Generator:
    return np.random.default_rng([cfg.seed, stream])


def _gray(name: str, **params) -> dict:
    d = {"type": name}
    for k, v in params.items():
        d[k] = {"type": "rgb", "value": float(v)} if k.endswith("reflectance") else v
    return d


def phong_dict(name, kd, ks, p) -> dict:
    return {"type": name, "diffuse_reflectance": {"type": "rgb", "value": float(kd)},
            "specular_reflectance": {"type": "rgb", "value": float(ks)}, "exponent": float(p)}


# --------------------------------------------------------------------------------------------
# Deterministic quadrature of the reflection equation
# --------------------------------------------------------------------------------------------

def _geometric_edges(lo: float, hi: float, start: float) -> list[float]:
    edges, e = [], start
    while e < hi:
        if e > lo:
            edges.append(e)
        e *= 2.0
    return edges


def hemisphere_quadrature(theta_i: float, width: float, n: int = 20):
    r"""Nodes and weights for ∫_{H+} g(ω) dω, refined around the mirror direction R(ω_i).

    Coordinates (α, φ) in the lobe-centred frame: ω = cos α R + sin α (cos φ T₁ + sin φ T₂),
    dω = sin α dα dφ, with R = (−sin θ_i, 0, cos θ_i), T₁ = (−cos θ_i, 0, −sin θ_i),
    T₂ = (0, 1, 0).  The upper hemisphere is exactly α < α_h(φ) = atan2(cos θ_i, sin θ_i cos φ)
    (where ω_z = cos α cos θ_i − sin α cos φ sin θ_i = 0), so the horizon is a panel edge and
    the integrand is smooth inside each panel: composite Gauss-Legendre with ``n`` nodes per
    panel, α panels doubling from width/4 (a lobe cos^p α has width ≈ 1/√p) plus an edge at
    α = π/2 (where max(0, cos α)^p has its kink), φ panels doubling away from π/2 (where
    α_h turns quickly at grazing incidence).  Only φ ∈ [0, π] is used and the weights are
    doubled: isotropic BSDFs with ω_i in the xz-plane are symmetric under y → −y.

    Returns:
        (wo (M, 3), weights (M,)) in float64.
    """
    c, s = math.cos(theta_i), math.sin(theta_i)
    R = np.array([-s, 0.0, c])
    T1 = np.array([-c, 0.0, -s])
    T2 = np.array([0.0, 1.0, 0.0])
    dphi = max(c, 1e-4) / 4.0
    side = _geometric_edges(0.0, math.pi / 2, dphi)
    phi_edges = np.array(sorted({0.0, math.pi, math.pi / 2} | {math.pi / 2 - e for e in side}
                                | {math.pi / 2 + e for e in side}))
    x, w = np.polynomial.legendre.leggauss(n)
    # φ nodes: composite Gauss-Legendre over the φ panels.
    h = 0.5 * np.diff(phi_edges)
    phi = (phi_edges[:-1, None] + h[:, None] * (x + 1.0)).ravel()
    wphi = (h[:, None] * w).ravel()
    alpha_h = np.arctan2(c, s * np.cos(phi))                          # horizon, per φ node
    # α panels: fixed edges clipped to [0, α_h(φ)]; panels past the horizon get zero width.
    edges = np.array([0.0] + sorted(set(_geometric_edges(0.0, math.pi, width / 4.0))
                                    | {math.pi / 2}) + [math.pi])
    lo = np.minimum(edges[None, :-1], alpha_h[:, None])               # (φ, panel)
    hi = np.minimum(edges[None, 1:], alpha_h[:, None])
    ha = 0.5 * (hi - lo)
    alpha = lo[..., None] + ha[..., None] * (x + 1.0)                  # (φ, panel, node)
    walpha = ha[..., None] * w
    keep = np.broadcast_to((ha > 0)[..., None], alpha.shape)
    al = alpha[keep]
    wts = (2.0 * np.broadcast_to(wphi[:, None, None], alpha.shape)[keep] * walpha[keep]
           * np.sin(al))
    ph = np.broadcast_to(phi[:, None, None], alpha.shape)[keep]
    sa, ca = np.sin(al), np.cos(al)
    dirs = (ca[:, None] * R + sa[:, None] * (np.cos(ph)[:, None] * T1 + np.sin(ph)[:, None] * T2))
    return dirs, wts


def directional_albedo(bsdf, theta_i: float, width: float, n: int = 20) -> float:
    """a(ω_i) = ∫ f_r(ω_i, ω_o) cos θ_o dω_o = ∫ eval dω_o, by :func:`hemisphere_quadrature`.

    With constant incident radiance L_i = 1 this is the reflected radiance L_r of the
    reflection equation (by reciprocity f_r(ω_i, ω_r) = f_r(ω_r, ω_i)).
    """
    wo, w = hemisphere_quadrature(theta_i, width, n)
    wo = wo / np.linalg.norm(wo, axis=1, keepdims=True)
    wi = np.broadcast_to(_dir(theta_i), wo.shape)
    return float(np.sum(w * bsdf_eval(bsdf, wi, wo)))


def _lobe_width(p: float) -> float:
    return 1.0 / math.sqrt(p + 2.0)


# --------------------------------------------------------------------------------------------
# Rendering helpers
# --------------------------------------------------------------------------------------------

def _render(cfg: Config, scene_name: str, stream: int, integrator=None, spp=None, passes=None,
            **params):
    """Load a scenes_xml/ scene with ``params`` and render it in passes: RenderResult."""
    from ..scenes import load_scene
    from ..render import render_scene

    scene = load_scene(scene_name, **{k: str(v) for k, v in params.items()})
    spp = int(spp or cfg.spp)
    return render_scene(scene, spp, seed=cfg.seed * 1000 + stream, passes=passes or cfg.passes,
                        integrator=integrator)


def _image_mean(res, channel: int | None = 0) -> tuple[float, float, float]:
    """Mean over pixels of one channel, its standard error (pixels are independent with a box
    filter: SE = √(Σ se²)/N), and the mean per-pixel standard deviation of one sample."""
    img = res.image[..., channel].astype(np.float64)
    se = res.stderr[..., channel].astype(np.float64)
    n = img.size
    return float(img.mean()), float(math.sqrt(np.sum(se * se)) / n), float(np.mean(se))


# --------------------------------------------------------------------------------------------
# 1. Energy
# --------------------------------------------------------------------------------------------

SPHERE_BIAS_NOTE = (
    "Mitsuba 3.9.1 sphere emitter: sample_direction() treats a point on the sphere as inside "
    "(|p − c| <= r(1 + 1500 eps)) and samples by area, while pdf_direction() treats it as "
    "outside unless r/|p − c| >= 1 − eps and returns the cone pdf 1/(2π); the MIS weights then "
    "do not sum to 1 and the estimate is biased high. Each strategy alone is exact; a cube "
    "enclosure is unbiased. See docs/checks.md.")


def _sphere_pdf_mismatch(cfg: Config) -> float:
    """Fraction of points on an emitting sphere (hit from inside) where the emitter's
    pdf_direction() disagrees (> 0.1 %) with the pdf its sample_direction() returned."""
    mi = _mi()
    scene = mi.load_dict({"type": "scene", "s": {
        "type": "sphere", "flip_normals": True, "bsdf": {"type": "diffuse"},
        "emitter": {"type": "area", "radiance": {"type": "rgb", "value": 1.0}}}})
    rng = _rng(cfg, 99)
    n = 1 << 14
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    si = scene.ray_intersect(mi.Ray3f(mi.Point3f(0.0, 0.0, 0.0), _vec(d)))
    u = rng.random((n, 2)).astype(np.float32)
    em = scene.emitters()[0]
    ds, _ = em.sample_direction(si, mi.Point2f(mi.Float(u[:, 0]), mi.Float(u[:, 1])))
    a, b = _arr(ds.pdf), _arr(em.pdf_direction(si, ds))
    return float(np.mean(np.abs(a - b) > 1e-3 * np.abs(a)))


def check_energy(cfg: Config) -> list[CheckResult]:
    """White furnace and the multi-bounce furnace for ``lambert`` and the built-in ``diffuse``.

    BSDF level, L_i = 1: the reflection-equation estimator with cosine-weighted directions
    (pdf cos θ_o/π) is eval/pdf = (ρ/π cos θ_o)/(cos θ_o/π) = ρ for every sample: zero variance,
    so every single sample must equal ρ to float32 precision (budget 16 ulp = 16·2⁻²⁴ ρ; the
    ratio of two float32 products rounds a few times).  The plugin's own ``sample`` weight too.

    Renders: check_furnace_sphere.xml (a convex sphere in a constant environment: every pixel
    ρ Le) with the path tracer (MIS of emitter and BSDF sampling: nonzero variance, statistical
    row) and with `direct` using BSDF sampling only (zero variance, exact row);
    check_furnace_enclosure.xml (camera inside a closed emitting enclosure: Le/(1 − ρ), or
    Le (1 − ρ^D)/(1 − ρ) for path length D).
    """
    mi = _mi()
    rows = _Rows("energy")
    rho = 0.7
    thetas = np.radians([0.0, 30.0, 60.0, 80.0, 89.0])
    n = max(1024, cfg.samples // len(thetas))
    tol = 16 * EPS32 * rho
    cfg.note("energy: BSDF level")
    for name in (cfg.lambert, "diffuse"):
        bsdf = mi.load_dict(_gray(name, reflectance=rho))
        rng = _rng(cfg, 1)
        wi = np.repeat(_dir(thetas), n, axis=0)
        u = rng.random((len(wi), 3))
        # Malley's method: cosine-weighted directions, pdf cos θ_o / π.
        wo = _arr(mi.warp.square_to_cosine_hemisphere(
            mi.Point2f(mi.Float(u[:, 1].astype(np.float32)), mi.Float(u[:, 2].astype(np.float32)))))
        pdf = wo[:, 2] / math.pi
        est = bsdf_eval(bsdf, wi, wo) / pdf
        worst = est[np.argmax(np.abs(est - rho))]
        per_angle = est.reshape(len(thetas), n).mean(axis=1)
        rows.exact(f"{name}: furnace, eval/cos-pdf", f"{name}: every sample of eval/pdf_cos "
                   f"(L_i = 1, θ_i 0..89°), worst", worst, rho, "ρ/π·cos / (cos/π) = ρ: zero variance",
                   tol, stderr=float(est.std() / math.sqrt(est.size)),
                   mean_per_angle=per_angle.tolist(), sample_std=float(est.std()))
        _, _, w = bsdf_sample(bsdf, wi, u)
        worst = w[np.argmax(np.abs(w - rho))]
        rows.exact(f"{name}: furnace, sample weight", f"{name}: every sample() weight "
                   f"(θ_i 0..89°), worst", worst, rho, "eval/pdf = ρ (cosine sampling)", tol,
                   stderr=float(w.std() / math.sqrt(w.size)), sample_std=float(w.std()))

    cfg.note("energy: furnace sphere")
    for k, name in enumerate((cfg.lambert, "diffuse")):
        res = _render(cfg, "check_furnace_sphere", 10 + k, bsdf=name, rho=rho)
        mean, se, px_se = _image_mean(res)
        rows.stat(f"{name}: furnace render, path (MIS)", f"{name}: sphere in constant Le = 1, "
                  f"path tracer, mean pixel", mean, rho, "convex: L = ρ Le (reflection eq.)", se,
                  pixel_stderr=px_se, nonzero_variance=bool(px_se > 0))
        direct = mi.load_dict({"type": "direct", "emitter_samples": 0, "bsdf_samples": 1})
        res = _render(cfg, "check_furnace_sphere", 20 + k, integrator=direct, bsdf=name, rho=rho,
                      passes=2)
        img = res.image[..., 0].astype(np.float64)
        worst = img.flat[np.argmax(np.abs(img - rho))]
        rows.exact(f"{name}: furnace render, BSDF only", f"{name}: same, `direct` with BSDF "
                   f"sampling only, worst pixel", worst, rho, "weight ρ per sample: zero variance",
                   tol, stderr=float(res.stderr[..., 0].max()))

    cfg.note("energy: closed enclosures")
    le = 1.0
    for k, name in enumerate((cfg.lambert, "diffuse")):
        r = 0.5
        d = 40
        res = _render(cfg, "check_furnace_enclosure", 30 + k, shape="cube", bsdf=name, rho=r,
                      le=le, max_depth=d)
        mean, se, _ = _image_mean(res)
        # Le (1 − ρ^D)/(1 − ρ): ρ^40 = 9e-13, i.e. Le/(1 − ρ) to float precision.
        rows.stat(f"{name}: cube enclosure ρ=0.5", f"{name}: inside an emitting closed cube, "
                  f"path (MIS), max_depth {d}", mean, le * (1 - r ** d) / (1 - r),
                  "L = Le/(1 − ρ) (Neumann series)", se)
    depth = 5
    for k, name in enumerate((cfg.lambert, "diffuse")):
        res = _render(cfg, "check_furnace_enclosure", 40 + k, shape="sphere", bsdf=name, rho=1.0,
                      le=le, max_depth=depth)
        mean, se, _ = _image_mean(res)
        rows.stat(f"{name}: sphere enclosure ρ=1 D=5", f"{name}: inside an emitting sphere, "
                  f"path (MIS), max_depth 5", mean, depth * le,
                  "L_D = Le (1 − ρ^D)/(1 − ρ) → D Le at ρ = 1", se, known_issue=SPHERE_BIAS_NOTE,
                  bias_per_bounce=(mean - depth * le) / (depth - 1))
    res = _render(cfg, "check_furnace_enclosure", 50, shape="cube", bsdf=cfg.lambert, rho=1.0,
                  le=le, max_depth=depth)
    mean, se, _ = _image_mean(res)
    rows.stat(f"{cfg.lambert}: cube enclosure ρ=1 D=5", f"{cfg.lambert}: same in a cube "
              f"(no sphere emitter)", mean, depth * le, "L_D = D Le at ρ = 1", se)
    mismatch = _sphere_pdf_mismatch(cfg)
    for k, (label, em, bs) in enumerate((("emitter only", 1, 0), ("BSDF only", 0, 1))):
        direct = mi.load_dict({"type": "direct", "emitter_samples": em, "bsdf_samples": bs})
        res = _render(cfg, "check_furnace_enclosure", 60 + k, integrator=direct, passes=2,
                      shape="sphere", bsdf=cfg.lambert, rho=1.0, le=le)
        img = res.image[..., 0].astype(np.float64)
        worst = img.flat[np.argmax(np.abs(img - 2 * le))]
        # Emitter sampling inside a sphere: cos θ cos θ' / d² = 1/(4R²) on every chord, so the
        # area-sampled estimate Le ρ/π · 4πR² · cos cos'/d² = ρ Le exactly: zero variance too.
        rows.exact(f"{cfg.lambert}: sphere, {label}", f"{cfg.lambert}: inside the sphere, "
                   f"`direct` {label}, worst pixel", worst, 2 * le,
                   "one bounce: Le + ρ Le, exact per sample", 64 * EPS32 * 2 * le,
                   stderr=float(res.stderr[..., 0].max()),
                   sphere_pdf_mismatch_fraction=mismatch)
    return rows.finish()


# --------------------------------------------------------------------------------------------
# 2. The reflection equation
# --------------------------------------------------------------------------------------------

#: Exponents of the Phong albedo grid (0 and >= 1000 included).
EXPONENTS = (0.0, 1.0, 10.0, 100.0, 1000.0, 10000.0, 100000.0)
#: Incidence angles (degrees) of the albedo grid.
INCIDENCE = (0.0, 30.0, 60.0, 75.0, 85.0)


def check_reflection(cfg: Config) -> list[CheckResult]:
    r"""The reflection equation through the plugins' eval, sample and a render.

    Quadrature (:func:`directional_albedo`) of eval over the hemisphere gives the albedo
    a(ω_i) = L_r under L_i = 1.  Exact expectations: lambert a = ρ at every angle; phong
    a = k_d + k_s at normal incidence (∫ cos^p α cos θ dω = 2π/(p+2) when R = N, times
    (p+2)/(2π)); and a ≤ 1 everywhere when k_d + k_s ≤ 1 (here k_d = k_s = 0.5, sum 1).
    Budget for these deterministic rows: 1e-5 absolute (float32 eval, ~2⁻²⁴ relative per node,
    summed in float64) plus 3 |Q(20) − Q(40)|, the quadrature's own error estimate from two
    node counts.  That estimate is ~1e-8 up to p = 1e4 but 4e-5 at p = 1e5, where float32
    cos α = ω_o·R (spacing 2⁻²⁴ near 1) turns cos^p α into a staircase: p·2⁻²⁴ ≈ 0.6 % per node.
    Monte Carlo: the mean of ``sample`` weights is an unbiased estimate of a(ω_i); rows per
    exponent with the worst angle, tolerance z·SE.  Render: check_furnace_plane.xml shows
    L_r = Le a(ω_r) at the camera direction.
    """
    mi = _mi()
    rows = _Rows("reflection")
    qtol = 1e-5
    cfg.note("reflection: lambert quadrature")
    rho = 0.7
    lam = mi.load_dict(_gray(cfg.lambert, reflectance=rho))
    alb = [directional_albedo(lam, math.radians(t), 1.0) for t in INCIDENCE]
    worst = alb[int(np.argmax(np.abs(np.array(alb) - rho)))]
    rows.exact(f"{cfg.lambert}: quadrature", f"{cfg.lambert}: ∫ eval dω by quadrature, "
               f"θ_i 0..85°, worst", worst, rho, "Lambert: ∫ ρ/π cos θ dω = ρ", qtol,
               per_angle=alb)

    kd, ks = 0.5, 0.5
    pho = mi.load_dict(phong_dict(cfg.phong, kd, ks, EXPONENTS[0]))
    params = mi.traverse(pho)
    n = max(1024, cfg.samples // len(INCIDENCE))
    grid, qerrs = {}, {}
    for p in EXPONENTS:
        cfg.note(f"reflection: phong p={p:g}")
        params["exponent"] = mi.Float(p)
        params.update()
        width = _lobe_width(p)
        quad = [directional_albedo(pho, math.radians(t), width) for t in INCIDENCE]
        grid[p] = quad
        # Error estimate of the quadrature (and of float32 eval, whose cos α near 1 is
        # quantized to 2⁻²⁴: a staircase at p = 1e5): |Q(20 nodes) − Q(40 nodes)| at θ_i = 0.
        qerr = abs(directional_albedo(pho, 0.0, width, n=40) - quad[0])
        qerrs[p] = qerr
        rows.exact(f"{cfg.phong} p={p:g}: normal incidence",
                   f"{cfg.phong} k_d={kd}, k_s={ks}, p={p:g}: quadrature albedo at θ_i = 0",
                   quad[0], kd + ks, "(p+2)/(2π) normalization: k_d + k_s", qtol + 3 * qerr,
                   quadrature_error=qerr)
        # Monte Carlo from sample(): mean weight, per angle; report the worst z.
        rng = _rng(cfg, 200 + int(min(p, 1e6)))
        best = None
        for t, q in zip(INCIDENCE, quad):
            wi = np.repeat(_dir(math.radians(t)), n, axis=0)
            _, _, w = bsdf_sample(pho, wi, rng.random((n, 3)))
            mean, se = float(w.mean()), float(w.std(ddof=1) / math.sqrt(n))
            z = abs(mean - q) / se if se > 0 else (0.0 if mean == q else math.inf)
            if best is None or z > best[0]:
                best = (z, t, mean, q, se)
        _, t, mean, q, se = best
        rows.stat(f"{cfg.phong} p={p:g}: sample() vs quadrature",
                  f"{cfg.phong} p={p:g}: mean sample() weight vs quadrature (worst of θ_i "
                  f"0..85°, here {t:g}°)", mean, q, "reflection-equation quadrature of eval", se,
                  tests=len(INCIDENCE), floor=qtol + 3 * qerr, theta_deg=t, samples=n)
    allv = np.array([v for q in grid.values() for v in q])
    rows.exact(f"{cfg.phong}: albedo <= 1", f"{cfg.phong} k_d + k_s = 1: max albedo over "
               f"θ_i 0..85° × p 0..1e5", float(allv.max()), 1.0, "energy conservation",
               qtol + 3 * max(qerrs.values()),
               relation="<=", grid={f"{p:g}": q for p, q in grid.items()})
    cfg.note("reflection: furnace plane renders")
    cases = [("lam", 0.0, 60.0), ("pho", 30.0, 0.0), ("pho", 30.0, 60.0), ("pho", 1000.0, 30.0)]
    for k, (mat, p, theta) in enumerate(cases):
        th = math.radians(theta)
        if mat == "lam":
            expected = directional_albedo(lam, th, 1.0)
            label = f"{cfg.lambert} ρ={rho}"
        else:
            params["exponent"] = mi.Float(p)
            params.update()
            expected = directional_albedo(pho, th, _lobe_width(p))
            label = f"{cfg.phong} p={p:g}"
        d = 5.0
        res = _render(cfg, "check_furnace_plane", 300 + k, material=mat, lambert=cfg.lambert,
                      phong=cfg.phong, rho=rho, kd=kd, ks=ks, exponent=p,
                      ox=f"{d * math.sin(th):.9g}", oz=f"{d * math.cos(th):.9g}")
        mean, se, _ = _image_mean(res)
        rows.stat(f"{label}: render θ_r={theta:g}°", f"{label}: plane under constant Le = 1, "
                  f"path tracer, mean pixel at θ_r = {theta:g}°", mean, expected,
                  "quadrature albedo a(ω_r) (reflection eq.)", se, floor=qtol)
    return rows.finish()


# --------------------------------------------------------------------------------------------
# 3. Lambert versus diffuse in a full scene
# --------------------------------------------------------------------------------------------

def holm(pvalues: np.ndarray) -> np.ndarray:
    """Holm's step-down adjusted p-values [Holm 1979]: max_{j<=k} min(1, (m − j + 1) p_(j))."""
    p = np.asarray(pvalues, dtype=np.float64).ravel()
    m = p.size
    order = np.argsort(p)
    adj = np.minimum(1.0, (m - np.arange(m)) * p[order])
    adj = np.maximum.accumulate(adj)
    out = np.empty(m)
    out[order] = adj
    return out.reshape(np.shape(pvalues))


def welch_pvalues(m1, se1, m2, se2, passes1: int, passes2: int) -> tuple[np.ndarray, np.ndarray]:
    """Two-sided Welch t-test p-values of per-pixel means with standard errors se1, se2.

    t = (m1 − m2)/√(se1² + se2²), Welch–Satterthwaite dof
    ν = (se1² + se2²)² / (se1⁴/(k1 − 1) + se2⁴/(k2 − 1)) with k the number of passes.
    Pixels with zero variance in both renders get p = 1 when equal, 0 otherwise.
    """
    from scipy.stats import t as student_t

    v1, v2 = np.asarray(se1, np.float64) ** 2, np.asarray(se2, np.float64) ** 2
    diff = np.asarray(m1, np.float64) - np.asarray(m2, np.float64)
    v = v1 + v2
    zero = v <= 0
    vs = np.where(zero, 1.0, v)
    t = diff / np.sqrt(vs)
    dof = vs * vs / np.maximum(v1 * v1 / (passes1 - 1) + v2 * v2 / (passes2 - 1), 1e-300)
    p = 2.0 * student_t.sf(np.abs(t), np.maximum(dof, 1.0))
    p = np.where(zero, np.where(diff == 0, 1.0, 0.0), p)
    return p, np.where(zero, 0.0, t)


def check_scene(cfg: Config) -> list[CheckResult]:
    """check_cornell_lambert.xml rendered with ``lambert`` and with ``diffuse``.

    The two renders use DIFFERENT seeds: with the same seed the two plugins consume the same
    random numbers identically and produce the same image (measured: bit-identical at 64 spp),
    which tests nothing statistical.  Each render is split into passes (per-pixel standard errors); a Welch t test
    per pixel and channel with Holm's correction at α = 0.01 must reject nothing, and the mean
    difference of each channel must lie within z·SE (Šidák over the 3 channels).  On failure
    the difference and t images are written to ``cfg.out_dir``.
    """
    from .. import exr

    rows = _Rows("scene")
    passes = max(cfg.passes, 16)
    cfg.note("scene: lambert render")
    a = _render(cfg, "check_cornell_lambert", 400, bsdf=cfg.lambert, passes=passes)
    cfg.note("scene: diffuse render")
    b = _render(cfg, "check_cornell_lambert", 401, bsdf="diffuse", passes=passes)
    p, t = welch_pvalues(a.image, a.stderr, b.image, b.stderr, passes, passes)
    adj = holm(p)
    rejected = int(np.sum(adj <= ALPHA))
    diff = a.image.astype(np.float64) - b.image.astype(np.float64)
    details: dict[str, Any] = {"min_holm_p": float(adj.min()), "pixels": int(p.size),
                               "passes": passes, "seeds": "different (see docs)"}
    row_px = rows.exact(f"{cfg.lambert} vs diffuse: per-pixel", f"Cornell box, all {cfg.lambert} "
                        f"vs all diffuse: pixels×channels rejected by Welch t (Holm, α=0.01)",
                        rejected, 0, "same BSDF: equal expected images", 0.0, **details)
    se_ch = np.sqrt(np.sum(a.stderr.astype(np.float64) ** 2 + b.stderr.astype(np.float64) ** 2,
                           axis=(0, 1))) / (diff.shape[0] * diff.shape[1])
    mean_ch = diff.mean(axis=(0, 1))
    worst = int(np.argmax(np.abs(mean_ch) / np.maximum(se_ch, 1e-300)))
    row_mean = rows.stat(f"{cfg.lambert} vs diffuse: mean difference", "Cornell box: mean "
                         f"difference over the image (worst of R, G, B: {'RGB'[worst]})",
                         float(mean_ch[worst]), 0.0, "same BSDF: expected difference 0",
                         float(se_ch[worst]), tests=3, mean_per_channel=mean_ch.tolist())
    result = rows.finish()
    if not (row_px.passed and row_mean.passed):
        cfg.out_dir.mkdir(parents=True, exist_ok=True)
        path = cfg.out_dir / f"scene_{cfg.lambert}_vs_diffuse_diff.exr"
        exr.write(path, diff.astype(np.float32), {"what": "lambert − diffuse"})
        exr.write(cfg.out_dir / f"scene_{cfg.lambert}_vs_diffuse_t.exr", t.astype(np.float32),
                  {"what": "Welch t statistic"})
        row_px.details["difference_image"] = str(path)
        row_mean.details["difference_image"] = str(path)
    return result


# --------------------------------------------------------------------------------------------
# 4. Radiance constancy
# --------------------------------------------------------------------------------------------

DISTANCES = (1.0, 10.0, 100.0, 1000.0)


def check_constancy(cfg: Config) -> list[CheckResult]:
    """Radiance constant along rays; irradiance 1/r²; mirror; dielectric L/n².

    Scenes (each header derives its value): check_constancy_emitter.xml (Le at every distance,
    zero variance: budget 8 ulp), check_furnace_plane.xml (a lambert plane under constant Le:
    ρ Le at every distance), check_irradiancemeter.xml (E = π Le a²/r², r = 1, 10),
    check_irradiance_probe.xml (r² L = 1 at r = 1..1000, a point source seen through a Lambertian
    probe: the irradiancemeter has no emitter sampling and cannot reach r = 1000),
    check_mirror.xml (Le), check_dielectric.xml (T Le/n² and T n² Le/(1 − F²)).
    """
    rows = _Rows("constancy")
    le = 1.0
    for k, d in enumerate(DISTANCES):
        cfg.note(f"constancy: distance {d:g}")
        res = _render(cfg, "check_constancy_emitter", 500 + k, dist=f"{d:g}", passes=2, spp=16)
        img = res.image[..., 0].astype(np.float64)
        worst = img.flat[np.argmax(np.abs(img - le))]
        rows.exact(f"emitter d={d:g}", f"emitting square seen from d = {d:g}: worst pixel",
                   worst, le, "radiance is constant along a ray", 8 * EPS32 * le,
                   stderr=float(res.stderr[..., 0].max()))
    rho = 0.7
    th = math.radians(60.0)
    for k, d in enumerate(DISTANCES):
        res = _render(cfg, "check_furnace_plane", 510 + k, material="lam", lambert=cfg.lambert,
                      rho=rho, ox=f"{d * math.sin(th):.9g}", oz=f"{d * math.cos(th):.9g}")
        mean, se, _ = _image_mean(res)
        rows.stat(f"{cfg.lambert} plane d={d:g}", f"{cfg.lambert} plane in constant Le = 1 seen "
                  f"from d = {d:g} at 60°: mean pixel", mean, rho * le,
                  "ρ Le at every distance (constancy + reflection eq.)", se)
    a = 0.5
    for k, r in enumerate((1.0, 10.0)):
        cfg.note(f"constancy: irradiancemeter r={r:g}")
        # A ray hits the source with probability (a/r)²: scale the samples with r².
        spp = 4096 * cfg.spp * int(max(1.0, r * r / 16))
        passes = 32
        res = _render(cfg, "check_irradiancemeter", 520 + k, dist=f"{r:g}", radius=a, spp=spp,
                      passes=passes)
        mean, se, _ = _image_mean(res)
        rows.stat(f"irradiancemeter r={r:g}", f"irradiancemeter E at r = {r:g} from a sphere "
                  f"a = {a} (× r² / (π Le a²))", mean * r * r / (math.pi * le * a * a), 1.0,
                  "E = π Le a²/r² (inverse square)", se * r * r / (math.pi * le * a * a),
                  dof=passes - 1,
                  E=mean, expected_E=math.pi * le * a * a / r ** 2, spp=spp)
    for k, r in enumerate(DISTANCES):
        res = _render(cfg, "check_irradiance_probe", 530 + k, dist=f"{r:g}", passes=2, spp=16,
                      lambert=cfg.lambert)
        img = res.image[..., 0].astype(np.float64) * r * r
        worst = img.flat[np.argmax(np.abs(img - 1.0))]
        # Budget: E varies by 1.5 h²/r² <= 1.8e-7 over the visible patch (scene header), plus
        # float32 rounding (16 ulp).
        rows.exact(f"{cfg.lambert} probe r={r:g}", f"r² × radiance of a ρ=1 {cfg.lambert} probe "
                   f"lit by a point source at r = {r:g}: worst pixel", worst, 1.0,
                   "E = I/r², L = ρE/π, I = π", 1.8e-7 + 16 * EPS32,
                   stderr=float(res.stderr[..., 0].max()) * r * r)
    cfg.note("constancy: mirror and dielectric")
    res = _render(cfg, "check_mirror", 540, passes=2, spp=16)
    img = res.image[..., 0].astype(np.float64)
    rows.exact("perfect mirror", "emitter seen in a perfect mirror (conductor 'none'): worst "
               "pixel", img.flat[np.argmax(np.abs(img - le))], le,
               "mirror keeps dA dω and F = 1: L = Le", 8 * EPS32 * le,
               stderr=float(res.stderr[..., 0].max()))
    n = 1.5
    F = ((n - 1) / (n + 1)) ** 2
    T = 1 - F
    for k, (label, cam_z, em_z, expected, why) in enumerate((
            ("dielectric, glass → air", 5, 0, T * le / n ** 2, "L/n² conserved: T Le / n²"),
            ("dielectric, air → glass", 0, 3, T * n * n * le / (1 - F * F),
             "L/n² conserved: T n² Le/(1 − F²)"))):
        res = _render(cfg, "check_dielectric", 550 + k, ior=n, cam_z=cam_z, em_z=em_z)
        mean, se, _ = _image_mean(res)
        rows.stat(label, f"{label}: radiance through a smooth interface, n = {n}, normal "
                  f"incidence", mean, expected, why, se, without_eta2_scaling=expected * (
                      n * n if cam_z > 1 else 1 / (n * n)))
    return rows.finish()


# --------------------------------------------------------------------------------------------
# 5. Snell refraction
# --------------------------------------------------------------------------------------------

INDICES = (1.33, 1.5, 2.4)


def check_snell(cfg: Config) -> list[CheckResult]:
    r"""Refraction directions and Fresnel, three ways, all deterministic.

    For relative indices η_rel = int_ior/ext_ior in {1.33, 1.5, 2.4} and their inverses, and
    incidence from both sides (400 angles 0..89.99° plus a band around the critical angle):
    ``phonglab.optics.refract`` (the seed's T = −ηV + (η V·N − √(1 − η²(1 − (V·N)²))) N, float64),
    ``mi.refract`` (float32) and the direction ``dielectric.sample`` returns with sample1 = 1 − 2⁻²⁴
    (transmission whenever F < 1).  Budget: angles agree within 8·2⁻²⁴·(1/cos θ_t) rad (float32
    directions; the refracted angle's sensitivity grows as 1/cos θ_t near grazing), here taken as
    its maximum over non-grazing cases 1e-5 rad; Snell residual |n₁ sin θ₁ − n₂ sin θ₂| ≤ 1e-6·n₁;
    Fresnel agreement within 8·2⁻²⁴(1 + 1/cos² θ_t) (F is steep near the critical angle);
    R + T = 1 within 1e-6.  TIR: the seed formula reports no
    transmitted ray exactly where ``dielectric`` reflects with F = 1, except within 1e-6 of the
    critical sin θ (float32 cannot tell them apart).
    """
    mi = _mi()
    from ..physics import optics

    rows = _Rows("snell")
    max_mi = max_bs = max_res = max_f = max_rt = max_w = 0.0
    tir_mismatch = tir_cases = 0
    min_f_tir = 1.0
    for n_rel in INDICES + tuple(1.0 / x for x in INDICES):
        int_ior, ext_ior = (n_rel, 1.0) if n_rel >= 1 else (1.0, 1.0 / n_rel)
        bsdf = mi.load_dict({"type": "dielectric", "int_ior": int_ior, "ext_ior": ext_ior})
        deg = np.linspace(0.0, 89.99, 400)
        for side in (+1, -1):
            # side +1: light arrives from outside (ext medium, on the normal's side).
            n1, n2 = (ext_ior, int_ior) if side > 0 else (int_ior, ext_ior)
            eta = n1 / n2
            crit = math.degrees(math.asin(min(1.0, 1.0 / eta))) if eta > 1 else None
            angles = deg if crit is None else np.concatenate(
                [deg, crit + np.linspace(-0.5, 0.5, 101)])
            th = np.radians(angles)
            v = _dir(th)
            v[:, 2] *= side
            normal = np.array([0.0, 0.0, float(side)])
            t_seed, valid = optics.refract(v, normal, eta)
            # mi.refract(wi, cos_theta_t, eta_ti), with cos_theta_t from mi.fresnel.
            # mi.fresnel takes the signed cos θ_i (< 0 inside) and η = int_ior / ext_ior.
            F_mi, cos_t, _, eta_ti = mi.fresnel(mi.Float(v[:, 2].astype(np.float32)),
                                                mi.Float(np.float32(int_ior / ext_ior)))
            t_mi = _arr(mi.refract(_vec(v), cos_t, eta_ti))
            u1 = np.full(len(v), 1.0 - EPS32)
            wo, pdf, w = bsdf_sample(bsdf, v, np.stack([u1, np.full(len(v), 0.5),
                                                        np.full(len(v), 0.5)], axis=1))
            bs_refl = wo[:, 2] * side > 0
            # Same float32-rounded cosine into both Fresnel implementations.
            F_seed, _ = optics.fresnel_dielectric(np.abs(v[:, 2].astype(np.float32)), eta)
            F_mi = _arr(F_mi)
            sin1 = np.sqrt(np.maximum(0.0, 1 - v[:, 2] ** 2))
            near_crit = np.abs(eta * sin1 - 1.0) < 1e-6
            ok = valid & ~near_crit
            tir = ~valid & ~near_crit
            tir_cases += int(tir.sum())
            tir_mismatch += int(np.sum(tir & ~bs_refl) + np.sum(ok & bs_refl))
            if tir.any():
                min_f_tir = min(min_f_tir, float(F_mi[tir].min()), float(pdf[tir].min()))

            def ang(a, b):
                c = np.clip(np.sum(a * b, axis=1) / (np.linalg.norm(a, axis=1)
                                                     * np.linalg.norm(b, axis=1)), -1.0, 1.0)
                return np.arccos(c)

            cos_t_seed = np.abs(t_seed[:, 2])
            good = ok & (cos_t_seed > 1e-2)   # grazing transmission: see docstring
            if good.any():
                max_mi = max(max_mi, float(ang(t_seed[good], t_mi[good]).max()))
                max_bs = max(max_bs, float(ang(t_seed[good], wo[good]).max()))
                # sin θ from the tangential components (from cos θ it loses precision near 0).
                sin_v = np.linalg.norm(v[good, :2], axis=1) / np.linalg.norm(v[good], axis=1)
                sin_t = np.linalg.norm(wo[good, :2], axis=1) / np.linalg.norm(wo[good], axis=1)
                max_res = max(max_res, float(np.abs(n1 * sin_v - n2 * sin_t).max() / n1))
                # Transmitted weight: (n1/n2)² scaling of radiance.
                max_w = max(max_w, float(np.abs(w[good] - eta * eta).max() / (eta * eta)))
            # F is steep near the critical angle: float32 rounding of 1 − η² sin² θ (≈ 2⁻²⁴)
            # moves cos θ_t by ≈ 2⁻²⁴/cos θ_t and F by ≈ 2⁻²⁴/cos² θ_t.  Budget per case:
            # b = 8·2⁻²⁴ (1 + 1/cos² θ_t); the row reports max |ΔF| / b (TIR: both exactly 1).
            cmp_f = (ok & (cos_t_seed > 1e-3)) | tir
            budget = np.where(tir, 8 * EPS32, 8 * EPS32 * (1.0 + 1.0 / np.maximum(
                cos_t_seed, 1e-3) ** 2))
            max_f = max(max_f, float((np.abs(F_seed - F_mi) / budget)[cmp_f].max()))
            # R + T: reflect with sample1 = 0 (pdf = F), transmit (pdf = 1 − F) where valid.
            _, pdf_r, _ = bsdf_sample(bsdf, v, np.stack([np.zeros(len(v)), np.full(len(v), 0.5),
                                                            np.full(len(v), 0.5)], axis=1))
            both = ok & (pdf_r < 1.0)
            if both.any():
                max_rt = max(max_rt, float(np.abs(pdf_r[both] + pdf[both] - 1.0).max()))
    rows.exact("refract: seed vs mi.refract", "max angle between optics.refract (seed formula) "
               "and mi.refract [rad]", max_mi, 0.0, "same law: identical directions", 1e-5)
    rows.exact("refract: seed vs dielectric", "max angle between optics.refract and the "
               "direction dielectric.sample transmits [rad]", max_bs, 0.0,
               "same law: identical directions", 1e-5)
    rows.exact("Snell law", "max |n₁ sin θ₁ − n₂ sin θ₂| / n₁ of dielectric's transmitted rays",
               max_res, 0.0, "Snell: n₁ sin θ₁ = n₂ sin θ₂", 1e-6)
    rows.exact("TIR: seed vs dielectric", f"cases where the seed's TIR test and dielectric's "
               f"choice disagree (of {tir_cases} TIR cases)", tir_mismatch, 0,
               "TIR iff η² sin² θ₁ > 1", 0.0)
    rows.exact("TIR: F = 1", "min Fresnel F (mi.fresnel) and reflect pdf past the critical angle",
               min_f_tir, 1.0, "total internal reflection: F = 1", 1e-6)
    rows.exact("Fresnel: seed vs mi.fresnel", "max |F(optics.fresnel_dielectric) − F(mi.fresnel)|"
               " / (8·2⁻²⁴ (1 + 1/cos² θ_t))", max_f, 1.0, "unpolarized Fresnel equations", 0.0,
               relation="<=")
    rows.exact("R + T = 1", "max |R + T − 1| of dielectric's sample pdfs (reflect, transmit)",
               max_rt, 0.0, "energy: smooth interface absorbs nothing", 1e-6)
    rows.exact("transmitted weight = η²", "max relative |weight − (n₁/n₂)²| of transmitted samples",
               max_w, 0.0, "Radiance mode: L/n² conserved", 1e-6)
    return rows.finish()


# --------------------------------------------------------------------------------------------
# 6. Sanity of the plugins
# --------------------------------------------------------------------------------------------

def _sanity_cases(cfg: Config) -> list[tuple[str, dict, float]]:
    """(label, plugin dict, exponent p for the float budget)."""
    cases = [(f"{cfg.lambert}", _gray(cfg.lambert, reflectance=0.7), 0.0),
             ("diffuse", _gray("diffuse", reflectance=0.7), 0.0)]
    for p in (0.0, 30.0, 300.0):
        cases.append((f"{cfg.phong} p={p:g}", phong_dict(cfg.phong, 0.4, 0.5, p), p))
    return cases


def _random_dirs(rng, n: int, grazing: int) -> np.ndarray:
    """Uniform directions on the sphere plus ``grazing`` ones with |cos θ| in [1e-7, 1e-2]."""
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    phi = rng.uniform(0, 2 * np.pi, grazing)
    cz = 10.0 ** rng.uniform(-7, -2, grazing) * rng.choice([-1.0, 1.0], grazing)
    s = np.sqrt(1 - cz * cz)
    g = np.stack([s * np.cos(phi), s * np.sin(phi), cz], axis=1)
    return np.concatenate([d, g])


def check_sanity(cfg: Config) -> list[CheckResult]:
    r"""Reciprocity, non-negativity/finiteness, weight = eval/pdf and χ², per plugin.

    * Reciprocity: f(ω_i, ω_o) = eval(ω_i → ω_o)/cos θ_o equals f(ω_o, ω_i); the relative
      difference over random pairs (both above the surface, incl. grazing ones) must stay within
      the float32 budget 32·2⁻²⁴·(p + 1): cos α = ω_o·R(ω_i) is rounded differently in the two
      orders, and cos^p α amplifies a relative error by p.
    * Non-negativity and finiteness of eval, pdf and sample weight over random directions on the
      whole sphere (below the horizon included) and grazing ones (|cos θ| down to 1e-7):
      the number of negative or non-finite values must be 0.
    * weight = eval/pdf at the sampled directions, relative budget 64·2⁻²⁴.
    * χ² test of sample() against pdf() (``mi.chi2.ChiSquareTest``, ``BSDFAdapter``) at
      θ_i ∈ {0°, 45°, 80°}; its p-value must exceed the Šidák level of all χ² tests of this check,
      and the histogram must not be empty (an empty one passes vacuously).  The expected cell
      counts integrate pdf() with 16 x 16 trapezoid points per cell (``ires=16``): with the
      default 4 x 4 a p = 300 lobe at normal incidence, narrower than one cos θ row of the
      101-row grid, is integrated too coarsely and the test rejects a correct sampler.
    """
    mi = _mi()
    rows = _Rows("sanity")
    cases = _sanity_cases(cfg)
    n = max(4096, cfg.samples // 4)
    chi2_angles = (0.0, 45.0, 80.0)
    chi2_level = sidak(ALPHA, len(cases) * len(chi2_angles))
    for k, (label, spec, p) in enumerate(cases):
        cfg.note(f"sanity: {label}")
        bsdf = mi.load_dict(spec)
        rng = _rng(cfg, 600 + k)
        up = _random_dirs(rng, n, n // 8)
        up[:, 2] = np.abs(up[:, 2])
        up2 = _random_dirs(rng, n, n // 8)
        up2[:, 2] = np.abs(up2[:, 2])
        f_io = bsdf_eval(bsdf, up, up2) / up2[:, 2]
        f_oi = bsdf_eval(bsdf, up2, up) / up[:, 2]
        scale = np.maximum(np.abs(f_io), np.abs(f_oi))
        rel = np.where(scale > 0, np.abs(f_io - f_oi) / np.where(scale > 0, scale, 1.0), 0.0)
        rows.exact(f"{label}: reciprocity", f"{label}: max relative |f(ωi,ωo) − f(ωo,ωi)| "
                   f"({len(up)} pairs, grazing incl.)", float(rel.max()), 0.0,
                   "Helmholtz reciprocity", 32 * EPS32 * (p + 1))
        wi = _random_dirs(rng, n, n // 8)
        wo = _random_dirs(rng, n, n // 8)
        ev, pd = bsdf_eval(bsdf, wi, wo), bsdf_pdf(bsdf, wi, wo)
        swo, spdf, sw = bsdf_sample(bsdf, wi, rng.random((len(wi), 3)))
        values = np.concatenate([ev, pd, sw, spdf])
        bad = int(np.sum(~np.isfinite(values)) + np.sum(values < 0)
                  + np.sum(~np.isfinite(swo)))
        rows.exact(f"{label}: non-negative, finite", f"{label}: negative or non-finite eval/pdf/"
                   f"sample values ({len(values)}, whole sphere + grazing)", bad, 0,
                   "f_r >= 0, pdf >= 0", 0.0)
        ok = (sw > 0) & (spdf > 0)
        ev_s = bsdf_eval(bsdf, wi[ok], swo[ok])
        pd_s = bsdf_pdf(bsdf, wi[ok], swo[ok])
        ratio = ev_s / np.where(pd_s > 0, pd_s, 1.0)
        relw = np.abs(sw[ok] - ratio) / np.maximum(np.abs(ratio), 1e-30)
        rows.exact(f"{label}: weight = eval/pdf", f"{label}: max relative |weight − eval/pdf| "
                   f"at sampled directions", float(relw.max()) if relw.size else math.inf, 0.0,
                   "sample() must agree with eval() and pdf()", 64 * EPS32)
        pmin, hist_min, per_angle = 1.0, math.inf, {}
        for t in chi2_angles:
            wi_c = _dir(math.radians(t))[0].tolist()
            sample_func, pdf_func = mi.chi2.BSDFAdapter(spec["type"], spec, wi=wi_c)
            test = mi.chi2.ChiSquareTest(domain=mi.chi2.SphericalDomain(), sample_func=sample_func,
                                         pdf_func=pdf_func, sample_dim=3,
                                         sample_count=cfg.chi2_samples, res=101, ires=16,
                                         seed=cfg.seed + k)
            test.run(significance_level=ALPHA, test_count=1, quiet=True)
            hist = float(np.sum(np.array(test.histogram)))
            pv = float(test.p_value) if test.p_value is not None else 0.0
            if test.fail or not math.isfinite(pv):
                pv = 0.0
            per_angle[f"{t:g}"] = {"p_value": pv, "histogram_sum": hist}
            pmin, hist_min = min(pmin, pv), min(hist_min, hist)
        rows.exact(f"{label}: χ² sampling", f"{label}: min χ² p-value of sample() vs pdf() "
                   f"(θ_i 0/45/80°)", pmin, chi2_level,
                   f"Pearson χ²; Šidák level over {len(cases) * len(chi2_angles)} tests", 0.0,
                   relation=">=", extra_ok=hist_min > 0, histogram_min_sum=hist_min,
                   per_angle=per_angle)
    return rows.finish()


# --------------------------------------------------------------------------------------------
# Running them
# --------------------------------------------------------------------------------------------

CHECKS: dict[str, Callable[[Config], list[CheckResult]]] = {
    "energy": check_energy,
    "reflection": check_reflection,
    "scene": check_scene,
    "constancy": check_constancy,
    "snell": check_snell,
    "sanity": check_sanity,
}


def run_checks(names=None, cfg: Config | None = None,
               on_check: Callable[[str], None] | None = None) -> list[CheckResult]:
    """Run the named checks (all by default) in the order of :data:`CHECK_NAMES`."""
    from ..errors import PhonglabError

    cfg = cfg or Config()
    names = list(names or CHECK_NAMES)
    unknown = [n for n in names if n not in CHECKS]
    if unknown:
        raise PhonglabError(f"unknown check {', '.join(map(repr, unknown))}; choose from "
                            f"{', '.join(CHECK_NAMES)}.")
    _mi()
    results: list[CheckResult] = []
    for name in [n for n in CHECK_NAMES if n in names]:
        if on_check:
            on_check(name)
        t0 = time.perf_counter()
        rows = CHECKS[name](cfg)
        for r in rows:
            r.details.setdefault("check_seconds", round(time.perf_counter() - t0, 2))
        results.extend(rows)
    return results


def format_table(results: list[CheckResult]) -> str:
    """The rows as a fixed-width text table."""
    head = ("check", "row", "measured", "expected", "stderr", "tol", "status")
    lines = []
    for r in results:
        rel = {"==": "", "<=": "≤ ", ">=": "≥ "}[r.relation]
        lines.append((r.check, r.name, _fmt(r.measured), rel + _fmt(r.expected), _fmt(r.stderr),
                      _fmt(r.tolerance), r.status))
    widths = [max(len(h), *(len(line[i]) for line in lines)) if lines else len(h)
              for i, h in enumerate(head)]
    out = ["  ".join(h.ljust(w) for h, w in zip(head, widths)),
           "  ".join("-" * w for w in widths)]
    for line in lines:
        out.append("  ".join(c.ljust(w) for c, w in zip(line, widths)))
    return "\n".join(out)


def _fmt(x: float) -> str:
    if isinstance(x, (int, np.integer)) or (isinstance(x, float) and x.is_integer()
                                            and abs(x) < 1e6):
        return f"{int(x)}"
    if not math.isfinite(x):
        return str(x)
    return f"{x:.6g}"


def write_json(path: str | Path, results: list[CheckResult], meta: dict | None = None) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    data = {"meta": _jsonable(meta or {}), "results": [r.to_dict() for r in results]}
    path.write_text(json.dumps(data, indent=2, ensure_ascii=False))
    return path
