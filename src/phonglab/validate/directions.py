"""Directions and sample values every kind draws: uniform directions on the sphere, an
orthonormal frame about a direction, and the largest float32 sample value below 1."""

from __future__ import annotations

import math

import numpy as np

#: The largest float32 below 1: a sample value's upper edge (Mitsuba's samplers never give 1).
ONE_MINUS = float(np.nextafter(np.float32(1.0), np.float32(0.0)))


def sphere(r: np.random.Generator, n: int) -> np.ndarray:
    """n uniform directions on the whole sphere (both hemispheres)."""
    z = 2.0 * r.random(n) - 1.0
    phi = 2.0 * np.pi * r.random(n)
    s = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    return np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=1)


def basis(n: np.ndarray) -> np.ndarray:
    """Rows s, t, n of an orthonormal frame with normal n (Duff et al. 2017, as
    Mitsuba's coordinate_system)."""
    n = np.asarray(n, np.float64) / np.linalg.norm(n)
    sign = math.copysign(1.0, n[2])
    a = -1.0 / (sign + n[2])
    b = n[0] * n[1] * a
    s = np.array([1.0 + sign * n[0] * n[0] * a, sign * b, -sign * n[0]])
    t = np.array([b, sign + n[1] * n[1] * a, -n[1]])
    return np.array([s, t, n])
