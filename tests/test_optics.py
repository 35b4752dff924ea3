"""phonglab.optics: the seed's reflection and refraction formulas against Snell's law and Mitsuba."""

from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

from phonglab.physics import optics

ETAS = [1 / 1.33, 1 / 1.5, 1 / 2.4, 1.33, 1.5, 2.4]   # n1/n2: entering, then leaving


def incident(theta):
    """Unit v away from the surface at angle theta from n = +z, in the xz plane."""
    theta = np.asarray(theta, dtype=float)
    return np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=-1)


def test_reflect_is_mirror():
    v = incident(np.linspace(0, math.pi / 2, 7))
    r = optics.reflect(v, np.array([0.0, 0.0, 1.0]))
    np.testing.assert_allclose(r, v * np.array([-1, -1, 1]), atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(r, axis=-1), 1.0)


@pytest.mark.parametrize("eta", ETAS, ids=[f"eta{e:.3f}" for e in ETAS])
def test_refract_obeys_snell_and_tir(eta):
    n1, n2 = eta, 1.0               # any pair with n1/n2 = eta
    theta = np.linspace(0.0, math.radians(89.99), 2001)
    v = incident(theta)
    n = np.array([0.0, 0.0, 1.0])
    t, valid = optics.refract(v, n, eta)
    crit = optics.critical_angle(eta)
    # TIR exactly past the critical angle (when going to the optically thinner medium).
    np.testing.assert_array_equal(valid, ~(theta > crit + 1e-12) | (eta <= 1))
    tv = t[valid]
    np.testing.assert_allclose(np.linalg.norm(tv, axis=-1), 1.0, atol=1e-12)
    assert np.all(tv[:, 2] < 0), "transmitted ray must cross to the other side"
    np.testing.assert_allclose(optics.snell_residual(v[valid], tv, n, n1, n2), 0.0, atol=1e-12)
    # In the plane of V and N, on the opposite side of N from V (tangential parts anti-parallel).
    np.testing.assert_allclose(tv[:, 1], 0.0, atol=1e-15)
    assert np.all(tv[:, 0] * v[valid][:, 0] <= 0)
    assert np.all(t[~valid] == 0)


@pytest.mark.parametrize("eta", ETAS, ids=[f"eta{e:.3f}" for e in ETAS])
def test_refract_matches_mitsuba(variant_llvm_rgb, eta):
    """Seed's formula (Dr.Jit branch) == mi.refract(wi, cos θ_t, eta_ti), whose eta_ti is
    Mitsuba's name for the seed's η = n1/n2 (mi.fresnel returns it as its 4th value)."""
    theta = np.linspace(0.0, math.radians(89.9), 500)
    v = incident(theta).astype(np.float32)
    vd = mi.Vector3f(*(mi.Float(v[:, k]) for k in range(3)))
    t, valid = optics.refract(vd, mi.Vector3f(0, 0, 1), mi.Float(eta))
    cos_theta_t = -dr.safe_sqrt(1 - (1 - mi.Float(v[:, 2]) ** 2) * eta * eta)
    t_mi = mi.refract(vd, cos_theta_t, eta)
    valid = np.array(valid)
    np.testing.assert_allclose(np.array(t)[:, valid], np.array(t_mi)[:, valid], atol=2e-6)
    # numpy (float64) and Dr.Jit (float32) branches agree to float32 precision.
    t64, valid64 = optics.refract(v.astype(float), np.array([0, 0, 1.0]), eta)
    np.testing.assert_array_equal(valid64, valid)
    np.testing.assert_allclose(np.array(t).T[valid], t64[valid], atol=2e-6)


def test_fresnel_energy_and_tir(variant_llvm_rgb):
    cos_i = np.linspace(1e-4, 1.0, 400)
    for eta in ETAS:
        F, cos_t = optics.fresnel_dielectric(cos_i, eta)
        assert np.all((F >= 0) & (F <= 1))
        F_mi, cos_t_mi, _, _ = mi.fresnel(mi.Float(cos_i.astype(np.float32)), 1.0 / eta)
        np.testing.assert_allclose(F, np.array(F_mi), atol=2e-5)
        tir = np.arccos(cos_i) > optics.critical_angle(eta)
        assert np.all(F[tir] == 1.0) and np.all(cos_t[tir] == 0.0)
    # Normal incidence: ((n1 - n2)/(n1 + n2))^2 = 0.04 for glass.
    np.testing.assert_allclose(optics.fresnel_dielectric(1.0, 1 / 1.5)[0], 0.04, rtol=1e-12)
