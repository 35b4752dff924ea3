r"""Geometric optics of the seed lecture: mirror reflection and Snell refraction.

Conventions (the seed's): ``v`` is a unit vector pointing *away* from the surface,
on the side of the unit normal ``n``; ``eta = n1 / n2`` is the ratio of the
refractive index on v's side to the index on the other side.

* Reflection:  R = 2 (N·V) N − V
* Refraction:  T = −η V + (η (V·N) − √(1 − η² (1 − (V·N)²))) N
  which satisfies n1 sin θ1 = n2 sin θ2, stays in the plane of V and N and
  points into the other medium.  When 1 − η² (1 − (V·N)²) < 0 there is no
  transmitted ray (total internal reflection): ``valid`` is False and ``t`` is 0.

Both functions accept numpy arrays of shape (..., 3) (computed in float64) and
Dr.Jit 3-vectors (computed in their own precision, vectorized).  Angles and
Fresnel reflectance for unpolarized light are provided for the checks, and the
angle between two directions (:func:`angle_between`) for comparing refracted rays.
"""

from __future__ import annotations

import numpy as np

# The Dr.Jit formulas live with the plugins, which may import only Mitsuba, Dr.Jit and numpy
# (not phonglab): one implementation per array kind, this module's numpy and theirs.
from ..plugins import _optics


def _is_drjit(x) -> bool:
    return type(x).__module__.startswith(("drjit", "mitsuba"))


def reflect(v, n):
    """Mirror direction R = 2 (N·V) N − V of v about n.

    Args:
        v: direction(s) away from the surface, numpy (..., 3) or a Dr.Jit Vector3f.
        n: unit normal(s), broadcastable against v.

    Returns:
        R, of the same kind as v.
    """
    if _is_drjit(v) or _is_drjit(n):
        return _optics.reflect(v, n)
    v, n = np.asarray(v, dtype=np.float64), np.asarray(n, dtype=np.float64)
    return 2.0 * np.sum(n * v, axis=-1, keepdims=True) * n - v


def refract(v, n, eta):
    """Refracted direction by the seed's formula, and whether it exists.

    Args:
        v: unit direction(s) away from the surface on n's side, numpy (..., 3) or Dr.Jit.
        n: unit normal(s) on v's side, broadcastable against v.
        eta: n1 / n2, the index on v's side over the index across the interface
            (a number or an array broadcastable to v's leading shape).

    Returns:
        (t, valid): t the unit transmitted direction (pointing into the second
        medium, away from n's side), zero where ``valid`` is False (total
        internal reflection).
    """
    if _is_drjit(v) or _is_drjit(n):
        return _optics.refract(v, n, eta)
    v, n = np.asarray(v, dtype=np.float64), np.asarray(n, dtype=np.float64)
    eta = np.asarray(eta, dtype=np.float64)
    cos_v = np.sum(v * n, axis=-1, keepdims=True)
    eta_b = eta[..., None] if eta.ndim else eta
    k = 1.0 - eta_b * eta_b * (1.0 - cos_v * cos_v)
    valid = k >= 0.0
    t = -eta_b * v + (eta_b * cos_v - np.sqrt(np.maximum(k, 0.0))) * n
    t = np.where(valid, t, 0.0)
    return t, valid[..., 0]


def critical_angle(eta) -> np.ndarray:
    """Incidence angle (radians) past which light going from n1 to n2 = n1/eta is totally
    reflected; π/2 (no TIR) when eta <= 1."""
    eta = np.asarray(eta, dtype=np.float64)
    return np.where(eta > 1.0, np.arcsin(np.minimum(1.0, 1.0 / np.maximum(eta, 1e-300))), np.pi / 2)


def fresnel_dielectric(cos_theta_i, eta):
    """Unpolarized Fresnel reflectance of a smooth dielectric interface.

    Args:
        cos_theta_i: cosine of the incidence angle (> 0, on the n1 side).
        eta: n1 / n2 as in :func:`refract`.

    Returns:
        (F, cos_theta_t): reflectance in [0, 1] (1 under total internal
        reflection) and the cosine of the transmitted angle (0 under TIR).
    """
    c = np.abs(np.asarray(cos_theta_i, dtype=np.float64))
    eta = np.asarray(eta, dtype=np.float64)
    sin2_t = eta * eta * np.maximum(0.0, 1.0 - c * c)
    tir = sin2_t >= 1.0
    cos_t = np.sqrt(np.maximum(0.0, 1.0 - sin2_t))
    # n1 cos θ_i vs n2 cos θ_t, divided by n2: eta cos θ_i and cos θ_t.
    r_s = (eta * c - cos_t) / (eta * c + cos_t)
    r_p = (c - eta * cos_t) / (c + eta * cos_t)
    F = np.where(tir, 1.0, 0.5 * (r_s * r_s + r_p * r_p))
    return F, np.where(tir, 0.0, cos_t)


def snell_residual(v, t, n, n1, n2):
    """|n1 sin θ1 − n2 sin θ2| for incident v (away from the surface) and transmitted t."""
    v, t, n = (np.asarray(a, dtype=np.float64) for a in (v, t, n))
    cos1 = np.abs(np.sum(v * n, axis=-1))
    cos2 = np.abs(np.sum(t * n, axis=-1))
    sin1 = np.sqrt(np.maximum(0.0, 1.0 - cos1 * cos1))
    sin2 = np.sqrt(np.maximum(0.0, 1.0 - cos2 * cos2))
    return np.abs(n1 * sin1 - n2 * sin2)


def angle_between(a, b) -> np.ndarray:
    """The angle [rad] between directions a and b, (..., 3) each (need not be unit length).

    atan2(|â × b̂|, â·b̂) keeps full precision for tiny angles, where arccos(â·b̂) loses it
    (an angle of 1e-8 rad is a cosine 5e-17 below 1, lost in float64).
    """
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    a = a / np.maximum(np.linalg.norm(a, axis=-1, keepdims=True), 1e-30)
    b = b / np.maximum(np.linalg.norm(b, axis=-1, keepdims=True), 1e-30)
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.sum(a * b, axis=-1))
