r"""Radiometry of the seed lecture, as numbers: flux, solid angle, radiance, the reflection equation.

The seed (D. Zorin, "Lighting", 2005) defines, and this module computes:

* flux through a small area crossed by particles of density N and speed v at angle θ
  to its normal: dΦ = N v cos θ dA;
* solid angle of a patch of area A on a sphere of radius R: Ω = A / R² (steradians;
  the whole sphere is 4π); exact forms for a cap, 2π (1 − cos θ), and for a disk seen on
  its axis, 2π (1 − d / √(d² + r²)), which A/R² approaches as the patch shrinks;
* radiance L: flux per unit area perpendicular to the ray per unit solid angle,
  dΦ = L cos θ dA dω;
* its constancy along a ray: for a thin pencil between patches dA₁, dA₂ at distance r,
  dω₁ = dA₂ cos θ₂ / r² and dω₂ = dA₁ cos θ₁ / r², so
  dA₁ cos θ₁ dω₁ = dA₂ cos θ₂ dω₂ = dA₁ cos θ₁ dA₂ cos θ₂ / r² (the étendue), and
  dΦ₁ = dΦ₂ gives L₁ = L₂;
* the reflection equation L_r(ω_r) = ∫_H² f_r(ω_i, ω_r) L_i(ω_i) cos θ_i dω_i, by
  quadrature of a Mitsuba BSDF's ``eval`` (which returns f_r cos θ of its second
  direction: with ``si.wi`` = ω_r, the viewer, and ``wo`` = ω_i, the light, the integrand is
  exactly ``eval · L_i``);
* the directional albedo a(ω_r) = ∫ f_r cos θ_i dω_i, the reflected radiance under a
  constant unit sky (the white furnace), estimated from a BSDF's ``sample`` as the mean
  sample weight (weight = f_r cos θ / pdf), with its standard error.

BSDFs are probed through :mod:`phonglab.probe` (directions in the local shading frame,
normal +z, both pointing away from the surface; ``probe.direction(θ, φ)`` builds them),
so any Mitsuba BSDF, built-in or plugin, works in any variant (JIT variants evaluate all
directions in one kernel launch).

Hemisphere quadrature: Gauss–Legendre in μ = cos θ on [0, 1] times the midpoint rule in φ,
dω = dμ dφ (exact for polynomials in μ up to degree 2 n_theta − 1 and trigonometric
polynomials in φ of degree < n_phi).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from .. import probe

#: Solid angle of the whole sphere, in steradians.
SPHERE_SOLID_ANGLE = 4.0 * math.pi


# ----------------------------------------------------------------------------- solid angle
def solid_angle(area, distance):
    """Ω = A / R²: solid angle of a small patch of area A facing the eye at distance R."""
    return np.asarray(area, dtype=np.float64) / np.asarray(distance, dtype=np.float64) ** 2


def solid_angle_cap(half_angle):
    """Ω = 2π (1 − cos θ): exact solid angle of a cone of half-angle θ (a spherical cap)."""
    return 2.0 * np.pi * (1.0 - np.cos(np.asarray(half_angle, dtype=np.float64)))


def solid_angle_disk(radius, distance):
    """Ω = 2π (1 − d / √(d² + r²)): exact solid angle of a disk of radius r seen on its axis
    from distance d (a cap of half-angle atan(r/d)); → π r²/d² as r/d → 0."""
    r = np.asarray(radius, dtype=np.float64)
    d = np.asarray(distance, dtype=np.float64)
    return 2.0 * np.pi * (1.0 - d / np.sqrt(d * d + r * r))


def solid_angle_rectangle(width, height, distance):
    """Ω = 4 arcsin(w h / √((w² + 4d²)(h² + 4d²))): exact solid angle of a w x h rectangle
    seen on its axis from distance d; → w h / d² = A/R² as d grows."""
    w, h = np.asarray(width, dtype=np.float64), np.asarray(height, dtype=np.float64)
    d = np.asarray(distance, dtype=np.float64)
    return 4.0 * np.arcsin(w * h / np.sqrt((w * w + 4 * d * d) * (h * h + 4 * d * d)))


def pixel_solid_angles(width: int, height: int, fov_x_degrees: float) -> np.ndarray:
    """Solid angle (H, W) of each pixel of a pinhole camera with horizontal field of view fov.

    A pixel of size dx dy on the image plane at unit distance, at (x, y), subtends
    dω = dx dy cos θ / r² = dx dy / (1 + x² + y²)^(3/2).
    """
    half = math.tan(math.radians(fov_x_degrees) / 2.0)
    dx = 2.0 * half / width
    x = (np.arange(width) + 0.5) * dx - half
    y = (np.arange(height) + 0.5) * dx - height * dx / 2.0
    xx, yy = np.meshgrid(x, y)
    return dx * dx / (1.0 + xx * xx + yy * yy) ** 1.5


def sphere_quadrature(n_theta: int = 32, n_phi: int = 64) -> tuple[np.ndarray, np.ndarray]:
    """Directions (N, 3) and weights (N,) integrating over the whole sphere (Σ w = 4π)."""
    x, w = np.polynomial.legendre.leggauss(n_theta)          # μ in [−1, 1]
    return _directions(x, w, n_phi)


def hemisphere_quadrature(n_theta: int = 64, n_phi: int = 128) -> tuple[np.ndarray, np.ndarray]:
    """Directions (N, 3) with z > 0 and weights (N,) integrating over the upper hemisphere
    (Σ w = 2π): Gauss–Legendre in μ = cos θ on [0, 1], midpoint rule in φ."""
    x, w = np.polynomial.legendre.leggauss(n_theta)
    return _directions(0.5 * (x + 1.0), 0.5 * w, n_phi)


def _directions(mu: np.ndarray, w_mu: np.ndarray, n_phi: int) -> tuple[np.ndarray, np.ndarray]:
    phi = (np.arange(n_phi) + 0.5) * (2.0 * np.pi / n_phi)
    mu_g, phi_g = np.meshgrid(mu, phi, indexing="ij")
    s = np.sqrt(np.maximum(0.0, 1.0 - mu_g * mu_g))
    dirs = np.stack([s * np.cos(phi_g), s * np.sin(phi_g), mu_g], axis=-1).reshape(-1, 3)
    weights = (w_mu[:, None] * np.full(n_phi, 2.0 * np.pi / n_phi)[None, :]).ravel()
    return dirs, weights


# ----------------------------------------------------------------------------- flux
def particle_flux(density, speed, area, theta):
    """dΦ = N v cos θ dA: particles per unit time through area dA tilted by θ to the flow."""
    return (np.asarray(density, dtype=np.float64) * speed * area
            * np.cos(np.asarray(theta, dtype=np.float64)))


def flux_from_radiance(radiance: Callable[[np.ndarray], np.ndarray] | float, area: float,
                       n_theta: int = 64, n_phi: int = 128) -> float:
    """Φ = A ∫_H² L(ω) cos θ dω: flux leaving a flat patch of area A with radiance L(ω).

    ``radiance`` is a number (a Lambertian emitter, Φ = π L A exactly) or a function of
    unit directions (N, 3) around the patch's normal +z returning (N,) radiances.
    """
    dirs, w = hemisphere_quadrature(n_theta, n_phi)
    L = np.full(len(w), float(radiance)) if np.isscalar(radiance) else np.asarray(radiance(dirs))
    return float(area * np.sum(w * L * dirs[:, 2]))


# ----------------------------------------------------------------------------- radiance along a ray
@dataclass
class Pencil:
    """A thin pencil of rays between patch 1 (emitting radiance L) and patch 2."""

    distance: np.ndarray        #: r
    d_omega_1: np.ndarray       #: solid angle of patch 2 seen from patch 1, dA₂ cos θ₂ / r²
    d_omega_2: np.ndarray       #: solid angle of patch 1 seen from patch 2, dA₁ cos θ₁ / r²
    etendue_1: np.ndarray       #: dA₁ cos θ₁ dω₁
    etendue_2: np.ndarray       #: dA₂ cos θ₂ dω₂
    flux: np.ndarray            #: dΦ = L dA₁ cos θ₁ dω₁, leaving 1 and arriving at 2
    radiance_1: np.ndarray      #: dΦ / (dA₁ cos θ₁ dω₁), radiance measured at patch 1
    radiance_2: np.ndarray      #: dΦ / (dA₂ cos θ₂ dω₂), radiance measured at patch 2


def pencil(radiance: float, area_1: float, area_2: float, theta_1: float, theta_2: float,
           distance) -> Pencil:
    """The seed's proof that radiance is constant along a ray, as numbers.

    Patch 1 (area dA₁, normal at θ₁ to the ray) emits radiance L towards patch 2 (dA₂, θ₂)
    at distance r.  Flux dΦ = L dA₁ cos θ₁ dω₁ falls as 1/r², but the radiance measured at
    either end, dΦ over its own (projected area x solid angle), stays L.
    """
    r = np.asarray(distance, dtype=np.float64)
    c1, c2 = math.cos(theta_1), math.cos(theta_2)
    d_omega_1 = area_2 * c2 / r ** 2
    d_omega_2 = area_1 * c1 / r ** 2
    e1 = area_1 * c1 * d_omega_1
    e2 = area_2 * c2 * d_omega_2
    flux = radiance * e1
    return Pencil(r, d_omega_1, d_omega_2, e1, e2, flux, flux / e1, flux / e2)


# ----------------------------------------------------------------------------- BSDFs
def reflected_radiance(bsdf, wo_view, incident: Callable[[np.ndarray], np.ndarray] | float = 1.0,
                       n_theta: int = 128, n_phi: int = 256) -> np.ndarray:
    """The reflection equation L_r(ω_r) = ∫_H² f_r(ω_i, ω_r) L_i(ω_i) cos θ_i dω_i, by quadrature.

    Args:
        bsdf: a Mitsuba BSDF (``mi.load_dict({"type": "phong", ...})``).
        wo_view: ω_r, unit direction towards the viewer in the local frame (normal +z),
            shape (3,), or several, shape (M, 3), evaluated in one kernel launch.
        incident: L_i, a number (a uniform sky) or a function of unit directions (N, 3)
            returning radiances (N,) or (N, channels).
        n_theta, n_phi: quadrature resolution (see the module docstring); sharp lobes
            (large Phong exponents) need more.

    Returns:
        L_r per channel, shape (channels,) for one view or (M, channels).  With
        ``incident=1`` this is the directional albedo.
    """
    views = np.asarray(wo_view, dtype=np.float64)
    single = views.ndim == 1
    views = views.reshape(-1, 3)
    dirs, w = hemisphere_quadrature(n_theta, n_phi)
    if np.isscalar(incident):
        L = np.full((len(w), 1), float(incident))
    else:
        L = np.asarray(incident(dirs), dtype=np.float64)
        L = L[:, None] if L.ndim == 1 else L
    m, n = len(views), len(dirs)
    # One launch over all (view, light direction) pairs: eval = f_r cos θ_i (Mitsuba's eval).
    f_cos = probe.eval(bsdf, np.repeat(views, n, axis=0), np.tile(dirs, (m, 1)))
    out = np.sum((w[:, None] * L)[None] * f_cos.reshape(m, n, -1), axis=1)
    return out[0] if single else out


@dataclass
class AlbedoEstimate:
    """Monte Carlo directional albedo from a BSDF's ``sample`` (the furnace test)."""

    mean: np.ndarray            #: per channel, mean of the sample weights
    stderr: np.ndarray          #: per channel, sd / √n
    n: int


def directional_albedo(bsdf, wi, n: int = 100_000, seed: int = 0) -> AlbedoEstimate:
    """a(ω_i) = ∫ f_r cos θ_o dω_o, estimated as the mean sample weight f_r cos θ_o / pdf.

    This is the radiance reflected towards ω_i under a constant unit sky (a white furnace),
    so a(ω_i) <= 1 for an energy-conserving BSDF; for phong a = k_d + k_s at normal incidence.
    """
    w = probe.sample_random(bsdf, wi, n, seed).weight
    return AlbedoEstimate(w.mean(axis=0), w.std(axis=0, ddof=1) / math.sqrt(n), n)
