r"""Exact values of the reflection-equation problems: deterministic float64 quadrature.

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
"""

from __future__ import annotations

import math

import numpy as np

from ...errors import PhonglabError
from .problem import Problem

#: Gauss–Legendre quadrature: panels × nodes per panel on each 1-D integral.
QUAD_PANELS = 256
QUAD_NODES = 32


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
