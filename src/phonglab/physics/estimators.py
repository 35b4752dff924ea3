r"""Monte Carlo estimators of the reflection equation at one surface point, and their exact values.

The quantity estimated is the radiance reflected towards ω_i (Mitsuba's ``si.wi``,
local shading frame, normal +Z) by a BSDF lit by a light of radiance L(ω_o)::

    L_r(ω_i) = ∫_{H²} f_r(ω_i, ω_o) L(ω_o) cos θ_o dω_o = ∫ eval(ω_i, ω_o) L(ω_o) dω_o

(Mitsuba's ``eval`` already carries cos θ_o).  Two lights are offered:

* ``constant``: L ≡ L_e over the whole sphere (a white furnace); L_r = L_e · albedo(ω_i).
* ``disk``: a distant disk light (a sun) of radiance L_e filling the cone of half-angle δ
  around the mirror direction R(ω_i) = 2(N·ω_i)N − ω_i, so the highlight sees it;
  solid angle Ω = 2π(1 − cos δ).

Estimators, each with N independent samples ω_k and the per-sample value X_k
(the estimate is the sample mean, its standard error s/√N with s the sample
standard deviation)::

    uniform   ω ~ uniform hemisphere, p = 1/(2π)          X = eval·L / p
    cosine    ω ~ cos θ/π (Malley)                        X = eval·L / p
    bsdf      ω, w = bsdf.sample(...) (the plugin's own)  X = w·L           (w = eval/pdf)
    light     disk: ω ~ uniform in the cone, p = 1/Ω;      X = eval·L_e / p
              constant: ω ~ uniform sphere, p = 1/(4π)    (the constant emitter's own sampling)
    mis       N/2 pairs (one bsdf + one light sample), power heuristic β = 2 [Veach 1997, §9.2]:
              X = f_b L_b/p_b · p_b²/(p_b²+p_l(ω_b)²) + f_l L_e/p_l · p_l²/(p_l²+p_b(ω_l)²)
    mis_optimal  pilot-chosen allocation n_b + n_l = N − M and optimal weights (below)

so every estimator draws N directions in total (MIS's N/2 pairs keep equal sample
counts; its standard error comes from the N/2 pair values).

``mis_optimal``: optimal MIS weights for the two strategies t ∈ {b, l} (BSDF and light
sampling) [Kondapaneni, Vévoda, Grittmann, Skřivan, Slusallek, Křivánek, "Optimal Multiple
Importance Sampling", ACM TOG 38(4), SIGGRAPH 2019, §4–5] with the allocation c_t = n_t/n
between them chosen from a pilot [Sbert, Havran, Szirmay-Kalos, "Multiple importance
sampling revisited: breaking the bounds", EURASIP J. Adv. Signal Process. 2018].  For a fixed
allocation the optimal weights are w_t = α_t p_t/f + (c_t p_t/Σ c p)(1 − Σ_k α_k p_k/f), and the
estimator they give is the balance heuristic applied to f − α·p plus the control variates
∫ p_t = 1::

    F = Σ_t α_t + (1/n) Σ_t Σ_{j ≤ n_t} (f(x_tj) − α·p(x_tj)) / (c·p(x_tj)),      x_tj ~ p_t
    A α = b,   A_tk = ∫ p_t p_k / (c·p) dx,   b_t = ∫ f p_t / (c·p) dx              (2×2)
    n·Var F = σ²(c) = ∫ (f − α·p)² / (c·p) dx       (at the solution: ∫ (f − α·p) p_t/(c·p) = 0)

F is unbiased for *any* α that does not depend on its own samples.  So the estimate spends
a pilot of M = n·:data:`PILOT_FRACTION` samples (at most :data:`PILOT_MAX`) (M/2 per strategy, i.e. drawn from q =
(p_b + p_l)/2) on choosing c and α, and *discards* it: for each candidate c_b in
:data:`ALLOCATIONS` (c_l = 1 − c_b) the pilot estimates A, b and ∫ f²/(c·p) by importance
sampling, Â = (1/M) Σ_m p pᵀ/((c·p) q) etc. (summed inside the pilot's kernel, in float64), solves the 2×2 system (a 1×1 one at c_b ∈ {0, 1},
where the absent strategy's α is 0) and keeps the c with the smallest σ̂²(c) = ∫̂ f²/(c·p) −
α̂·b̂ (the pure strategy when within :data:`PURE_PREFERENCE` of it: heavy tails make the
pilot optimistic about mixtures).  The other n − M samples, drawn from fresh streams, give F
(the kernel sums their residuals per estimate, in float64).  Its standard error is stratified: Var F = Σ_t n_t s_t²/n², s_t² the sample variance within
strategy t.  A BSDF sample that the plugin rejects (pdf 0, a lobe direction below the
horizon) is a point of its own with probability 1 − ∫_{H²} p_b; giving it p_b := 1, p_l = 0,
f = 0 makes its value −α_b/c_b, which is what keeps ∫ p_b = 1 (the control variate) true,
and the "1" cancels in every term above.  With f = α·p exactly (a pure lobe inside the
light, a pure light under a wide lobe) σ² = 0 for every c, so no split is penalized.

Exact values come from deterministic quadrature in float64 (:func:`exact_value`).
Around the lobe axis R write ω_o = cos α R + sin α (cos φ e₁ + sin φ e₂), e₁ in the
plane of R and N, so cos θ_o = A + B cos φ with A = cos α cos θ_R, B = sin α sin θ_R.
The φ integral of the horizon-clipped cosine has a closed form::

    h(A, B) = (1/2π) ∫₀^{2π} max(0, A + B cos φ) dφ = (A φ₀ + B sin φ₀)/π,  φ₀ = arccos(clip(−A/B, −1, 1))

(= max(0, A) when B = 0).  With the lobe measure substituted (u = cos^{p+1} α, so
(p+1)/(2π) cos^p α dω = du dφ/2π) the specular part is a smooth 1-D integral::

    spec = k_s L_e (p+2)/(p+1) ∫_{u_min}^1 h(A(α(u)), B(α(u))) du,   cos α(u) = u^{1/(p+1)}

with u_min = 0 for the constant light and cos^{p+1} δ for the disk (the cone *is* the
lobe's polar cap, both being centred on R).  The diffuse part is
k_d L_e · 2 ∫_{cos δ}^1 h(c cos θ_R, √(1−c²) sin θ_R) dc (k_d L_e for the constant
light).  Closed forms checked by the tests: normal incidence, disk: spec = k_s L_e
(1 − cos^{p+2} δ), diffuse = k_d L_e sin² δ; constant light: spec = k_s L_e.

Every parameter that a sweep changes (exponent, ω_i, light axis, cos δ, L_e, seed)
enters the kernel as an opaque Dr.Jit value, so a sweep compiles each estimator
once; :class:`Estimate` records the first call's JIT compile time separately.

References: E. Veach, *Robust Monte Carlo Methods for Light Transport Simulation*,
PhD thesis, Stanford 1997, ch. 9; M. Pharr, W. Jakob, G. Humphreys, *Physically
Based Rendering*, 4th ed., §2.2 (importance sampling) and §2.2.3 (MIS).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import drjit as dr
import mitsuba as mi
import numpy as np

from .. import probe, registration
from ..errors import PhonglabError

#: Estimator names, in the order charts and tables list them.
METHODS: tuple[str, ...] = ("uniform", "cosine", "bsdf", "light", "mis", "mis_optimal")
#: Estimators whose N samples are independent and identically distributed (all but the
#: two-stage ``mis_optimal``, whose samples follow a pilot-chosen allocation).
IID_METHODS: tuple[str, ...] = METHODS[:5]
#: ``mis_optimal``: the pilot's share of the N samples (discarded after it chose α and c).
PILOT_FRACTION = 1.0 / 32.0
#: ``mis_optimal``: the largest pilot (its 2×2 solves cost host time per candidate c).
PILOT_MAX = 2048
#: ``mis_optimal``: the candidate BSDF shares c_b of the main samples (c_l = 1 − c_b).
ALLOCATIONS = tuple(k / 8.0 for k in range(9))
#: ``mis_optimal``: a pure strategy (c_b = 0 or 1) is preferred over a mixture whose pilot
#: variance is not below (1 − this) times the pure strategy's.
PURE_PREFERENCE = 0.1
LIGHTS: tuple[str, ...] = ("constant", "disk")

#: Gauss–Legendre quadrature: panels × nodes per panel on each 1-D integral.
QUAD_PANELS = 256
QUAD_NODES = 32


@dataclass(frozen=True)
class Problem:
    """One reflection-equation integral: the BSDF, the incidence and the light.

    Attributes:
        bsdf: ``"phong"`` or ``"lambert"`` (phonglab's plugins, whose exact values
            :func:`exact_value` knows), or a Mitsuba built-in (``"diffuse"``; no exact value).
        diffuse_reflectance: k_d (ρ for ``lambert``/``diffuse``), grey.
        specular_reflectance: k_s (``phong`` only), grey.
        exponent: p (``phong`` only).
        theta_i: incidence angle of ω_i in degrees, in [0, 90).
        light: ``"constant"`` or ``"disk"``.
        half_angle: δ of the disk light in degrees.
        radiance: L_e.
    """

    bsdf: str = "phong"
    diffuse_reflectance: float = 0.0
    specular_reflectance: float = 1.0
    exponent: float = 100.0
    theta_i: float = 30.0
    light: str = "disk"
    half_angle: float = 3.0
    radiance: float = 1.0

    def __post_init__(self):
        if self.light not in LIGHTS:
            raise PhonglabError(f"unknown light {self.light!r}; use one of {', '.join(LIGHTS)}")
        if not 0.0 <= self.theta_i < 90.0:
            raise PhonglabError(f"theta_i must lie in [0, 90) degrees, got {self.theta_i}")
        if not 0.0 < self.half_angle < 90.0:
            raise PhonglabError(f"half_angle must lie in (0, 90) degrees, got {self.half_angle}")
        if not (math.isfinite(self.exponent) and self.exponent >= 0):
            raise PhonglabError(f"exponent must be finite and >= 0, got {self.exponent}")

    @property
    def wi(self) -> tuple[float, float, float]:
        """ω_i in the local frame: (sin θ_i, 0, cos θ_i)."""
        return tuple(float(c) for c in probe.direction(math.radians(self.theta_i)))

    @property
    def label(self) -> str:
        if self.bsdf == "phong":
            mat = (f"phong kd={self.diffuse_reflectance:g} ks={self.specular_reflectance:g} "
                   f"p={self.exponent:g}")
        else:
            mat = f"{self.bsdf} rho={self.diffuse_reflectance:g}"
        light = "constant light" if self.light == "constant" else f"disk {self.half_angle:g}deg"
        return f"{mat}, {light}, theta_i={self.theta_i:g}deg"


@dataclass
class Estimate:
    """S independent estimates of one :class:`Problem` with N samples each.

    Attributes:
        method: estimator name.
        n: samples per estimate (MIS: n/2 pairs).
        values: (S,) float64 estimates (sample means).
        stderr: (S,) float64 standard errors s/√n of each estimate.
        nan_count / inf_count: non-finite per-sample values over all S·n samples.
        seconds: wall time of the call (trace + kernel + transfer).
        compile_ms: JIT compile time inside this call (codegen + backend, ms; 0 on a
            kernel-cache hit).
        kernels: kernels launched; cache_hits: how many of them were cached.
        sample_variance: pooled per-sample variance s² (over all S·n samples around
            their batch means).
        kernel_hashes: Dr.Jit hashes of the kernels launched (equal hashes = no recompile).
    """

    method: str
    n: int
    values: np.ndarray
    stderr: np.ndarray
    nan_count: int
    inf_count: int
    seconds: float
    compile_ms: float
    kernels: int
    cache_hits: int
    sample_variance: float
    kernel_hashes: list = field(default_factory=list)

    @property
    def value(self) -> float:
        return float(self.values[0])

    @property
    def is_zero_variance(self) -> bool:
        """Whether every sample took (up to float32 rounding) the same value."""
        scale = float(np.nanmax(np.abs(self.values))) if self.values.size else 0.0
        return bool(np.isfinite(self.sample_variance)
                    and self.sample_variance <= (8 * 2.0 ** -24 * scale) ** 2)


# --------------------------------------------------------------------------------------------
# Exact values (float64 quadrature)
# --------------------------------------------------------------------------------------------

def _gauss_legendre(a: float, b: float, panels: int = QUAD_PANELS,
                    nodes: int = QUAD_NODES, graded: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Composite Gauss–Legendre nodes and weights on [a, b].

    ``graded`` > 0 adds panel edges a + (b − a)·2⁻ᵏ, k = 1..graded: a geometric mesh towards
    a, where u ↦ u^{1/(p+1)} has its singular derivative (exponential convergence there).
    """
    x, w = np.polynomial.legendre.leggauss(nodes)
    edges = np.linspace(a, b, panels + 1)
    if graded:
        edges = np.unique(np.concatenate([edges, a + (b - a) * 2.0 ** -np.arange(1, graded + 1)]))
    half = 0.5 * np.diff(edges)[:, None]
    mid = 0.5 * (edges[:-1] + edges[1:])[:, None]
    return (mid + half * x).ravel(), (half * w).ravel()


def clipped_cosine_mean(A, B):
    """h(A, B) = (1/2π)∫ max(0, A + B cos φ) dφ = (A φ₀ + B sin φ₀)/π, φ₀ = arccos(clip(−A/B))."""
    A = np.asarray(A, np.float64)
    B = np.abs(np.asarray(B, np.float64))
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(B > 0, -A / np.where(B > 0, B, 1.0), np.where(A >= 0, -1.0, 1.0))
    phi0 = np.arccos(np.clip(ratio, -1.0, 1.0))
    return (A * phi0 + B * np.sin(phi0)) / np.pi


def exact_value(problem: Problem, panels: int = QUAD_PANELS, nodes: int = QUAD_NODES) -> float:
    """L_r(ω_i) of ``problem`` by float64 quadrature (closed form in φ, Gauss–Legendre in u).

    Raises:
        PhonglabError: for a BSDF other than ``phong``, ``lambert`` or ``diffuse``.
    """
    if problem.bsdf not in ("phong", "lambert", "diffuse"):
        raise PhonglabError(f"no exact value for bsdf {problem.bsdf!r}; use phong, lambert or "
                            f"diffuse")
    theta_r = math.radians(problem.theta_i)        # the mirror direction's polar angle
    cos_r, sin_r = math.cos(theta_r), math.sin(theta_r)
    Le = problem.radiance
    kd = problem.diffuse_reflectance
    ks = problem.specular_reflectance if problem.bsdf == "phong" else 0.0
    p = problem.exponent
    disk = problem.light == "disk"
    # The kernel holds cos δ as a float32 (opaque) value and its cone is exactly
    # {ω : ω·R >= float32(cos δ)}; for δ = 1° that rounding alone changes 1 − cos δ by
    # ~10⁻⁴ relative, so the exact value is computed for the float32 cone.
    cos_delta = float(np.float32(math.cos(math.radians(problem.half_angle))))

    # Diffuse lobe k_d/π ∫ L cos θ_o dω: k_d L_e under the constant light; over the cone
    # around R, with c = cos γ uniform in [cos δ, 1]: k_d/π · 2π ∫ h(c cos θ_R, s sin θ_R) dc.
    if not disk:
        diffuse = kd * Le
    else:
        c, w = _gauss_legendre(cos_delta, 1.0, panels, nodes)
        s = np.sqrt(np.maximum(0.0, 1.0 - c * c))
        diffuse = kd * Le * 2.0 * float(np.sum(w * clipped_cosine_mean(c * cos_r, s * sin_r)))

    specular = 0.0
    if ks > 0:
        # u = cos^{p+1} α  ⇔  cos α = exp(ln u / (p+1)); u_min = cos^{p+1} δ for the cap.
        log_u_min = (p + 1.0) * math.log(cos_delta) if disk else -math.inf
        u_min = math.exp(log_u_min) if disk else 0.0
        u, w = _gauss_legendre(u_min, 1.0, panels, nodes, graded=64)
        cos_a = np.exp(np.log(u) / (p + 1.0))
        sin_a = np.sqrt(np.maximum(0.0, 1.0 - cos_a * cos_a))
        integral = float(np.sum(w * clipped_cosine_mean(cos_a * cos_r, sin_a * sin_r)))
        specular = ks * Le * (p + 2.0) / (p + 1.0) * integral
    return diffuse + specular


def exact_normal_incidence(problem: Problem) -> float:
    """Closed form at θ_i = 0: disk k_d L_e sin²δ + k_s L_e (1 − cos^{p+2}δ); constant k_d + k_s."""
    ks = problem.specular_reflectance if problem.bsdf == "phong" else 0.0
    kd, Le = problem.diffuse_reflectance, problem.radiance
    if problem.light == "constant":
        return (kd + ks) * Le
    d = math.radians(problem.half_angle)
    return kd * Le * math.sin(d) ** 2 + ks * Le * (1.0 - math.cos(d) ** (problem.exponent + 2.0))


# --------------------------------------------------------------------------------------------
# The Dr.Jit estimators
# --------------------------------------------------------------------------------------------

def kernel_stats(hashes: list | None = None) -> tuple[float, int, int]:
    """(compile ms, kernels, cache hits) of the JIT kernels launched since the last call.

    Reads (and so clears) ``dr.kernel_history()``; appends each kernel's hash to ``hashes``
    when given.
    """
    ms, count, hits = 0.0, 0, 0
    for k in dr.kernel_history():
        if str(k.get("type", "")).endswith("JIT"):
            count += 1
            hits += int(bool(k.get("cache_hit", 0)))
            ms += float(k.get("codegen_time", 0.0)) + float(k.get("backend_time", 0.0))
            if hashes is not None:
                hashes.append(k.get("hash"))
    return ms, count, hits


@dataclass(frozen=True)
class KernelLight:
    """A :class:`Problem`'s light inside the kernel: L(ω), its own sampling and that density.

    ``axis`` (the mirror direction R), ``cos_cutoff`` (cos δ) and ``radiance`` (L_e) are
    opaque Dr.Jit values, so a new problem reuses the compiled kernel.
    """

    constant: bool              #: the constant light (else the disk)
    axis: mi.Vector3f           #: R = 2(N·ω_i)N − ω_i, the cone's axis
    cos_cutoff: mi.Float        #: cos δ
    radiance: mi.Float          #: L_e

    @classmethod
    def of(cls, problem: Problem) -> "KernelLight":
        wi = problem.wi
        return cls(problem.light == "constant",
                   dr.opaque(mi.Vector3f, (-wi[0], -wi[1], wi[2])),     # R = 2(N·ω_i)N − ω_i
                   dr.opaque(mi.Float, math.cos(math.radians(problem.half_angle))),
                   dr.opaque(mi.Float, problem.radiance))

    def emitted(self, wo):
        """L(ω_o): L_e inside the cone (disk) or everywhere (constant)."""
        if self.constant:
            return dr.full(mi.Float, 1.0, dr.width(wo)) * self.radiance
        inside = dr.dot(wo, self.axis) >= self.cos_cutoff
        return dr.select(inside, self.radiance, 0.0)

    def sample(self, sample2):
        """(ω, pdf) of the light's own sampling: uniform in the cone (disk) or on the sphere."""
        if self.constant:
            wo = mi.warp.square_to_uniform_sphere(sample2)
            return wo, mi.warp.square_to_uniform_sphere_pdf(wo)
        local = mi.warp.square_to_uniform_cone(sample2, self.cos_cutoff)
        return mi.Frame3f(self.axis).to_world(local), \
            mi.warp.square_to_uniform_cone_pdf(local, self.cos_cutoff)

    def pdf(self, wo):
        """The density of :meth:`sample` at ω_o: 1/(4π), or 1/Ω inside the cone and 0 outside."""
        if self.constant:
            return dr.full(mi.Float, dr.inv_four_pi, dr.width(wo))
        inside = dr.dot(wo, self.axis) >= self.cos_cutoff
        return dr.select(inside, dr.rcp(dr.two_pi * (1.0 - self.cos_cutoff)), 0.0)


@dataclass(frozen=True)
class Integrand:
    """eval(ω_i, ω) · L(ω) at one surface point: the BSDF, its interaction, the light."""

    bsdf: mi.BSDF
    si: mi.SurfaceInteraction3f     #: si.wi = ω_i (local frame)
    light: KernelLight
    ctx: mi.BSDFContext


def _interaction(problem: Problem) -> mi.SurfaceInteraction3f:
    """A one-lane interaction whose ``wi`` = ω_i is an opaque Dr.Jit value (all else zero).

    Not :func:`phonglab.probe.interaction`, which is the numpy-side bridge: with it (ω_i in a
    one-lane buffer made from numpy) the sweep of tests/test_estimators.py launched kernels of
    a new hash after :meth:`ReflectionEstimators.set`, i.e. recompiled, where ``dr.opaque``
    keeps one kernel per estimator.  The phonglab plugins and ``diffuse`` read only ``si.wi``
    (and constant textures) here.
    """
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = dr.opaque(mi.Vector3f, problem.wi)
    return si


def _safe_ratio(value, pdf):
    """value / pdf where pdf > 0, else 0 (no 0/0 or x/0 for a sample the density never draws)."""
    return dr.select(pdf > 0, value / dr.select(pdf > 0, pdf, 1.0), 0.0)


# One function per estimator (module docstring): the per-sample value X from the uniform
# numbers u1 (lobe choice), u2 (direction) and, for MIS's second sample, the stream rng.
def _uniform(f: Integrand, u1, u2, rng):
    """ω ~ uniform hemisphere, p = 1/(2π): X = eval · L · 2π."""
    wo = mi.warp.square_to_uniform_hemisphere(u2)
    return f.bsdf.eval(f.ctx, f.si, wo) * (f.light.emitted(wo) * dr.two_pi)


def _cosine(f: Integrand, u1, u2, rng):
    """ω ~ cos θ/π (Malley): X = eval · L / p."""
    wo = mi.warp.square_to_cosine_hemisphere(u2)
    pdf = mi.warp.square_to_cosine_hemisphere_pdf(wo)
    return f.bsdf.eval(f.ctx, f.si, wo) * _safe_ratio(f.light.emitted(wo), pdf)


def _bsdf(f: Integrand, u1, u2, rng):
    """ω, w = bsdf.sample: X = w · L (w = eval / pdf)."""
    bs, weight = f.bsdf.sample(f.ctx, f.si, u1, u2)
    return weight * f.light.emitted(bs.wo)


def _light(f: Integrand, u1, u2, rng):
    """ω ~ the light's own sampling: X = eval · L_e / p."""
    wo, pdf = f.light.sample(u2)
    return f.bsdf.eval(f.ctx, f.si, wo) * _safe_ratio(f.light.radiance, pdf)


def _mis(f: Integrand, u1, u2, rng):
    """One BSDF sample and one light sample, power heuristic β = 2 [Veach 1997, §9.2]."""
    bs, weight = f.bsdf.sample(f.ctx, f.si, u1, u2)
    p_b = bs.pdf
    p_l = f.light.pdf(bs.wo)
    w_b = dr.select(p_b > 0, dr.square(p_b) / (dr.square(p_b) + dr.square(p_l)), 0.0)
    value = weight * (f.light.emitted(bs.wo) * w_b)
    u3 = mi.Point2f(rng.next_float32(), rng.next_float32())
    wo, p_l = f.light.sample(u3)
    f_l, p_b = f.bsdf.eval_pdf(f.ctx, f.si, wo)
    w_l = dr.select(p_l > 0, dr.square(p_l) / (dr.square(p_l) + dr.square(p_b)), 0.0)
    return value + f_l * _safe_ratio(f.light.radiance * w_l, p_l)


def _technique(f: Integrand, is_b, u1, u2):
    """(f, p_b, p_l) at one sample of BSDF sampling where ``is_b``, else of light sampling.

    A symbolic ``if``: a lane runs only its own technique (the LLVM backend skips a branch
    that no lane of a packet takes).  A BSDF sample the plugin rejects (pdf 0, e.g. a lobe
    direction below the horizon) is the *null point* of that technique: f = 0, p_l = 0 and
    p_b := 1 (any positive value; it cancels, module docstring).
    """
    def by_bsdf(u1, u2):
        bs, weight = f.bsdf.sample(f.ctx, f.si, u1, u2)
        valid = bs.pdf > 0
        value = _channel_mean(weight) * bs.pdf * f.light.emitted(bs.wo)     # eval · L
        return (dr.select(valid, value, 0.0), dr.select(valid, bs.pdf, 1.0),
                dr.select(valid, f.light.pdf(bs.wo), 0.0))

    def by_light(u1, u2):
        wo, p_l = f.light.sample(u2)
        value, p_b = f.bsdf.eval_pdf(f.ctx, f.si, wo)
        return _channel_mean(value) * f.light.radiance, p_b, p_l

    return dr.if_stmt((u1, u2), is_b, by_bsdf, by_light)


def _row_sums(values: list, row, rows: int) -> np.ndarray:
    """(rows, K) float64 sums of K Dr.Jit arrays over the lanes of each row.

    A scatter-add inside the kernel (``ReduceMode.Local``: reduced within each SIMD packet
    first) into one (rows + 1)·K buffer at the opaque index row·K + k, read back at once.  Not
    ``dr.block_sum``, whose block size is a kernel literal (a new N would recompile), nor the
    automatic mode, which compiles a kernel per buffer size.
    """
    k = len(values)
    target = dr.zeros(mi.Float64, (rows + 1) * k)
    base = row * dr.opaque(mi.UInt32, k)
    for i, value in enumerate(values):
        dr.scatter_reduce(dr.ReduceOp.Add, target, mi.Float64(value), base + i,
                          mode=dr.ReduceMode.Local)
    dr.eval(target)
    return np.array(target, dtype=np.float64)[:rows * k].reshape(rows, k)


def weighted_moments(fv, pb, pl, c_b: float, select):
    """The six per-sample terms w·(p_b², p_b p_l, p_l², f p_b, f p_l, f²), w = 1/((c·p) q), whose
    pilot means are A, b and ∫ f²/(c·p) at the BSDF share c_b (q = (p_b + p_l)/2, the pilot's
    mixture).  Plain arithmetic plus ``select`` (np.where or dr.select): the one formula for
    numpy arrays and for Dr.Jit arrays inside the pilot kernel."""
    d = (c_b * pb + (1.0 - c_b) * pl) * (0.5 * (pb + pl))
    w = select(d > 0, 1.0 / select(d > 0, d, 1.0), 0.0)
    wf = w * fv
    return [w * pb * pb, w * pb * pl, w * pl * pl, wf * pb, wf * pl, wf * fv]


def solve_allocation(mom: np.ndarray, uncovered_b: np.ndarray, uncovered_l: np.ndarray,
                     allocations=ALLOCATIONS) -> tuple[np.ndarray, ...]:
    """(c_b, α_b, α_l, σ²(c_b)) per row from the pilot's moments.

    Args:
        mom: (B, G, 6) pilot means of :func:`weighted_moments` for each candidate c_b.
        uncovered_b / uncovered_l: (B,) whether a pilot sample had f ≠ 0 where p_b (p_l) = 0.
        allocations: the G candidate BSDF shares c_b (c_l = 1 − c_b).

    For each c the 2×2 system A α = b (A = mean w p pᵀ, b = mean w f p) is the pilot's estimate
    of Kondapaneni et al.'s moment matrix and vector, and σ²(c) = mean w f² − αᵀ b the
    per-sample variance of the optimally weighted estimator (module docstring).  At c_b = 0
    or 1 only the present technique's α is fitted (the other is 0), and σ² is infinite when
    that technique alone misses part of f (``uncovered``).  The smallest σ² wins, a pure
    strategy (c_b ∈ {0, 1}) when it is within :data:`PURE_PREFERENCE` of the best.
    """
    abb, abl, all_, bb, bl, sff = np.moveaxis(np.asarray(mom, np.float64), -1, 0)
    det = abb * all_ - abl * abl
    good = det > 1e-9 * abb * all_
    safe = np.where(good, det, 1.0)
    fit_b = bb / np.where(abb > 0, abb, 1.0)
    alpha_b = np.where(good, (bb * all_ - bl * abl) / safe, fit_b)
    alpha_l = np.where(good, (bl * abb - bb * abl) / safe, 0.0)
    ends = np.asarray(allocations, np.float64)
    pure_b, pure_l = ends == 1.0, ends == 0.0
    alpha_b = np.where(pure_b, fit_b, np.where(pure_l, 0.0, alpha_b))
    alpha_l = np.where(pure_l, bl / np.where(all_ > 0, all_, 1.0), np.where(pure_b, 0.0, alpha_l))
    sigma2 = sff - alpha_b * bb - alpha_l * bl
    # Below 10⁻¹² of the second moment it is float64 rounding of an exact fit (σ² = 0).
    sigma2 = np.where(sigma2 <= 1e-12 * sff, 0.0, sigma2)
    # Inside (0, 1) c·p > 0 at every sample (each has p_b > 0 or p_l > 0).
    sigma2 = np.where(pure_b & np.asarray(uncovered_b, bool)[:, None], np.inf, sigma2)
    sigma2 = np.where(pure_l & np.asarray(uncovered_l, bool)[:, None], np.inf, sigma2)
    best = np.argmin(sigma2, axis=1)
    rows = np.arange(len(best))
    for end in (np.flatnonzero(pure_b), np.flatnonzero(pure_l)):
        if end.size:
            e = int(end[0])
            best = np.where(sigma2[:, e] * (1.0 - PURE_PREFERENCE) <= sigma2[rows, best], e, best)
    return ends[best], alpha_b[rows, best], alpha_l[rows, best], sigma2[rows, best]


def choose_allocation(fv: np.ndarray, pb: np.ndarray, pl: np.ndarray,
                      allocations=ALLOCATIONS) -> tuple[np.ndarray, ...]:
    """:func:`solve_allocation` from (B, M) float64 pilot samples f, p_b, p_l (numpy): the first
    M/2 of each row drawn by BSDF sampling, the rest by light sampling (null points carry
    p_b = 1, p_l = 0, f = 0).  The estimator computes the same moments inside its kernel."""
    mom = np.stack([np.stack([t.mean(axis=1) for t in weighted_moments(fv, pb, pl, c, np.where)],
                             axis=-1) for c in allocations], axis=1)
    return solve_allocation(mom, np.any((pb == 0) & (fv != 0), axis=1),
                            np.any((pl == 0) & (fv != 0), axis=1), allocations)


#: The estimators by name (the order of :data:`METHODS`).
_ESTIMATORS = {"uniform": _uniform, "cosine": _cosine, "bsdf": _bsdf, "light": _light,
               "mis": _mis}
#: A seed offset that keeps ``mis_optimal``'s pilot streams apart from its main streams.
_PILOT_KEY = 0x6A09E667


def _load_bsdf(problem: Problem):
    """The BSDF of ``problem`` (a phonglab plugin or Mitsuba's ``diffuse``)."""
    if problem.bsdf == "phong":
        spec = {"type": "phong", "diffuse_reflectance": problem.diffuse_reflectance,
                "specular_reflectance": problem.specular_reflectance,
                "exponent": float(problem.exponent)}
    elif problem.bsdf in ("lambert", "diffuse"):
        spec = {"type": problem.bsdf, "reflectance": problem.diffuse_reflectance}
    else:
        raise PhonglabError(f"unsupported bsdf {problem.bsdf!r} for the estimators; use "
                            f"phong, lambert or diffuse")
    try:
        return mi.load_dict(spec)
    except Exception as exc:
        raise PhonglabError(f"cannot create the {problem.bsdf} BSDF: {exc}") from exc


def _channel_mean(spectrum):
    """Mean over colour channels (the problems are grey, so all channels agree)."""
    channels = [spectrum[k] for k in range(len(spectrum))]
    return sum(channels[1:], channels[0]) * (1.0 / len(channels))


class ReflectionEstimators:
    """The five estimators of one BSDF, re-targetable to any :class:`Problem` without recompiling.

    The BSDF is loaded once per (type, k_d, k_s); the exponent is changed through
    ``mi.traverse`` + ``params.update()`` (phong keeps it opaque); ω_i, the light
    axis, cos δ, L_e and the seed are opaque Dr.Jit values.

    Example::

        est = ReflectionEstimators(Problem(exponent=100, theta_i=30))
        e = est.run("mis", n=2**14, seed=0)
        print(e.value, e.stderr[0], est.exact())
    """

    #: Largest number of per-sample values one launch brings back to the host.
    CHUNK = 1 << 22

    def __init__(self, problem: Problem):
        registration.register()
        if not mi.variant().startswith(("llvm_", "cuda_")):
            raise PhonglabError(f"the estimators need a JIT variant (llvm_ad_rgb), not "
                                f"{mi.variant()}; call phonglab.register('llvm_ad_rgb') first")
        self.problem = problem
        self._material = None
        self._load(problem)

    def _load(self, problem: Problem) -> None:
        material = (problem.bsdf, problem.diffuse_reflectance, problem.specular_reflectance)
        if material != self._material:
            self.bsdf = _load_bsdf(problem)
            self.params = mi.traverse(self.bsdf)
            self._material = material
        if problem.bsdf == "phong" and float(self.params["exponent"][0]) != problem.exponent:
            self.params["exponent"] = mi.Float(float(problem.exponent))
            self.params.update()
        self.integrand = Integrand(self.bsdf, _interaction(problem), KernelLight.of(problem),
                                   mi.BSDFContext())
        self.problem = problem

    def set(self, problem: Problem | None = None, **changes) -> "ReflectionEstimators":
        """Re-target to ``problem`` (or the current one with ``changes``); no recompilation."""
        self._load(replace(problem or self.problem, **changes))
        return self

    def exact(self) -> float:
        return exact_value(self.problem)

    @staticmethod
    def _uniforms(n_total: int, seed: int):
        """(lane index, u1, u2) of n_total lanes; lane k draws from PCG32 stream TEA(seed, k)."""
        idx = dr.arange(mi.UInt32, n_total)
        v0, v1 = mi.sample_tea_32(dr.opaque(mi.UInt32, seed & 0xFFFFFFFF), idx)
        rng = mi.PCG32(size=n_total)
        rng.seed(mi.UInt64(v0), mi.UInt64(v1))
        u1 = rng.next_float32()
        return idx, u1, mi.Point2f(rng.next_float32(), rng.next_float32()), rng

    def _samples(self, method: str, n_total: int, seed: int):
        """Per-sample values X (a Dr.Jit Float of n_total entries; MIS: of pairs).

        Sample k draws from PCG32 stream TEA(seed, k): u1, then u2 (then MIS's u3).
        """
        if method not in _ESTIMATORS:
            raise PhonglabError(f"unknown estimator {method!r}; use one of {', '.join(METHODS)}")
        _, u1, u2, rng = self._uniforms(n_total, seed)
        return _channel_mean(_ESTIMATORS[method](self.integrand, u1, u2, rng))

    def _pilot(self, m: int, batches: int, seed: int) -> tuple[np.ndarray, ...]:
        """(c_b, α_b, α_l, σ²) per row from a pilot of m/2 BSDF then m/2 light samples a row.

        The kernel sums :func:`weighted_moments` for every candidate c_b per row (float64), so only (batches, G, 6) means and two coverage flags per row come back;
        :func:`solve_allocation` does the 2×2 solves on the host.
        """
        idx, u1, u2, _ = self._uniforms(m * batches, seed ^ _PILOT_KEY)
        row = mi.UInt32(dr.floor((mi.Float64(idx) + 0.5) * dr.opaque(mi.Float64, 1.0 / m)))
        j = idx - row * dr.opaque(mi.UInt32, m)
        fv, pb, pl = (mi.Float64(x) for x in
                      _technique(self.integrand, j < dr.opaque(mi.UInt32, m // 2), u1, u2))
        terms = [t for c in ALLOCATIONS for t in weighted_moments(fv, pb, pl, c, dr.select)]
        zero = mi.Float64(0.0)
        terms += [dr.select((pb == 0) & (fv != 0), 1.0, zero),
                  dr.select((pl == 0) & (fv != 0), 1.0, zero)]
        out = _row_sums(terms, row, batches) / m
        mom = out[:, :-2].reshape(batches, len(ALLOCATIONS), 6)
        return solve_allocation(mom, out[:, -2] > 0, out[:, -1] > 0)

    def _optimal_sums(self, per: int, n_b: np.ndarray, alpha_b: np.ndarray,
                      alpha_l: np.ndarray, seed: int) -> dict[str, np.ndarray]:
        """Per-row sums of ``mis_optimal``'s main stage: row s draws n_b[s] BSDF samples then
        per − n_b[s] light samples, weighted with its own α (module docstring).

        The kernel sums its residuals R = X − α_b − α_l per row (float64, :func:`_row_sums`), so
        only a few numbers per row come back: Σ R and Σ R² over the BSDF samples and over all,
        and the NaN and Inf counts.  α as the kernel holds them (float32) come back too.
        """
        batches = len(n_b)
        idx, u1, u2, _ = self._uniforms(per * batches, seed)
        # row = ⌊k / per⌋ in float64 (exact here: k < 2³², per ≤ 2²²), not a UInt32 division,
        # which the LLVM backend scalarizes (it cost as much as the BSDF sample itself).
        row = mi.UInt32(dr.floor((mi.Float64(idx) + 0.5) * dr.opaque(mi.Float64, 1.0 / per)))
        width = dr.opaque(mi.UInt32, per)

        def table(kind, values, dtype):
            # Padded to >= 2 entries: a 1-entry gather source compiles a different kernel.
            return dr.gather(kind, kind(np.append(values, values[-1:]).astype(dtype)), row)

        is_b = (idx - row * width) < table(mi.UInt32, n_b, np.uint32)
        fv, pb, pl = _technique(self.integrand, is_b, u1, u2)
        a_b = table(mi.Float, alpha_b, np.float32)
        a_l = table(mi.Float, alpha_l, np.float32)
        c_b = table(mi.Float, n_b / per, np.float32)
        r = _safe_ratio(fv - a_b * pb - a_l * pl, c_b * pb + (1.0 - c_b) * pl)
        r64 = mi.Float64(r)
        sq = r64 * r64
        zero = mi.Float64(0.0)
        names = ("sum_b", "sum", "sq_b", "sq", "nan", "inf")
        sums = _row_sums([dr.select(is_b, r64, zero), r64, dr.select(is_b, sq, zero), sq,
                          dr.select(dr.isnan(r), 1.0, zero), dr.select(dr.isinf(r), 1.0, zero)],
                         row, batches)
        out = {k: sums[:, i] for i, k in enumerate(names)}
        out["alpha"] = (alpha_b.astype(np.float32).astype(np.float64)
                        + alpha_l.astype(np.float32).astype(np.float64))
        return out

    @staticmethod
    def pilot_size(n: int) -> int:
        """Pilot samples of an n-sample ``mis_optimal`` estimate: n·PILOT_FRACTION, even, in
        [32, PILOT_MAX]."""
        return min(PILOT_MAX, max(32, 2 * int(round(n * PILOT_FRACTION / 2))))

    def _run_optimal(self, n: int, batches: int, seed: int) -> tuple:
        """(values, stderr, NaN count, Inf count) of ``batches`` mis_optimal estimates, in chunks
        of <= CHUNK samples."""
        m = self.pilot_size(n)
        per = n - m
        rows = max(1, self.CHUNK // n)
        values, stderr, nan, inf = [], [], 0, 0
        for c, b0 in enumerate(range(0, batches, rows)):
            b = min(rows, batches - b0)
            chunk_seed = seed if c == 0 else (seed * 0x9E3779B1 + c) & 0xFFFFFFFF
            c_b, alpha_b, alpha_l, _ = self._pilot(m, b, chunk_seed)
            n_b = np.rint(c_b * per).astype(np.int64)
            t = self._optimal_sums(per, n_b, alpha_b, alpha_l, chunk_seed)
            values.append(t["alpha"] + t["sum"] / per)
            # Stratified: Var = Σ_t k_t s_t² / per², s_t² the variance within technique t.
            var = np.zeros(b)
            for k, total, squares in ((n_b, t["sum_b"], t["sq_b"]),
                                      (per - n_b, t["sum"] - t["sum_b"], t["sq"] - t["sq_b"])):
                ss = np.maximum(squares - total * total / np.maximum(k, 1), 0.0)
                var += ss / np.maximum(k - 1, 1) * k
            stderr.append(np.sqrt(var) / per)
            nan += int(t["nan"].sum())
            inf += int(t["inf"].sum())
        return np.concatenate(values), np.concatenate(stderr), nan, inf

    def _values(self, method: str, per: int, batches: int, seed: int) -> np.ndarray:
        """(batches, per) float64 per-sample values, launched in chunks of <= CHUNK samples."""
        rows = max(1, self.CHUNK // per)
        out = []
        for c, b0 in enumerate(range(0, batches, rows)):
            b = min(rows, batches - b0)
            chunk_seed = seed if c == 0 else (seed * 0x9E3779B1 + c) & 0xFFFFFFFF
            x = self._samples(method, per * b, chunk_seed)
            dr.eval(x)
            out.append(np.array(x, dtype=np.float64).reshape(b, per))
        return out[0] if len(out) == 1 else np.concatenate(out)

    def run(self, method: str, n: int, seed: int = 0, batches: int = 1) -> Estimate:
        """``batches`` independent estimates with ``n`` samples each, vectorized.

        Args:
            method: one of :data:`METHODS`.
            n: samples per estimate (MIS draws n/2 pairs; n >= 2).
            seed: the random seed (sample k of the launch uses PCG32 stream TEA(seed, k)).
            batches: S, the number of independent estimates.
        """
        if method not in METHODS:
            raise PhonglabError(f"unknown estimator {method!r}; use one of {', '.join(METHODS)}")
        if n < 2 or batches < 1:
            raise PhonglabError(f"need n >= 2 samples and batches >= 1, got n={n}, batches={batches}")
        if method == "mis_optimal" and n < 2 * self.pilot_size(n):
            raise PhonglabError(f"mis_optimal needs n >= {2 * self.pilot_size(n)} samples (a pilot of "
                                f"{self.pilot_size(n)} and a main stage), got n={n}")
        dr.set_flag(dr.JitFlag.KernelHistory, True)
        dr.kernel_history()                              # clear
        t0 = time.perf_counter()
        if method == "mis_optimal":
            values, stderr, nan_count, inf_count = self._run_optimal(n, batches, seed)
        else:
            per = n // 2 if method == "mis" else n      # MIS: n/2 pairs of 2 samples
            arr = self._values(method, per, batches, seed)
            values = arr.mean(axis=1)
            dev = arr - values[:, None]
            stderr = np.sqrt(np.einsum("ij,ij->i", dev, dev) / max(per - 1, 1) / per)
            nan_count = int(np.isnan(arr).sum())
            inf_count = int(np.isinf(arr).sum())
        seconds = time.perf_counter() - t0
        hashes: list[str] = []
        compile_ms, kernels, hits = kernel_stats(hashes)
        # Per-sample variance in the units of n: an n-sample estimate has variance σ²/n.
        per_n = n // 2 if method == "mis" else n
        return Estimate(method, n, values, stderr, nan_count, inf_count, seconds,
                        compile_ms, kernels, hits, float(np.mean(stderr ** 2)) * per_n, hashes)

    def moments(self, method: str, n: int = 1 << 22, seed: int = 0xC0FFEE) -> tuple[float, float, float]:
        """(mean, variance σ², excess kurtosis γ₂) of the per-sample value X, from n samples.

        For MIS, X is the value of one pair (two samples), so that an n-sample estimate
        has variance σ²/(n/2).  ``mis_optimal``'s samples are not identically distributed:
        σ² is n times the variance of one n-sample estimate (stratified), γ₂ is NaN.
        """
        if method == "mis_optimal":
            e = self.run(method, n, seed=seed)
            return e.value, e.sample_variance, float("nan")
        per = n // 2 if method == "mis" else n
        arr = self._values(method, per, 1, seed).ravel()
        mean = float(arr.mean())
        dev = arr - mean
        m2 = float(np.mean(dev * dev))
        m4 = float(np.mean(dev ** 4))
        return mean, m2 * per / max(per - 1, 1), (m4 / (m2 * m2) - 3.0) if m2 > 0 else 0.0

    def time_steady(self, method: str, n: int, repeats: int = 5, seed: int = 0) -> tuple[float, Estimate]:
        """Median wall time of ``repeats`` single estimates after one warm-up call (the JIT one)."""
        first = self.run(method, n, seed=seed)
        times = [self.run(method, n, seed=seed + 1 + r).seconds for r in range(repeats)]
        return float(np.median(times)), first
