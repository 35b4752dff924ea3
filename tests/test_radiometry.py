"""phonglab.physics.radiometry: the seed's radiometry as numbers, checked against closed forms.

Cheapest first: solid angles and quadrature (float64, deterministic) → the pencil of rays →
the reflection equation by quadrature of the plugins' eval (deterministic; float32 eval) →
Monte Carlo albedo from the plugins' sample and a furnace render (statistical: α = 0.01,
Šidák over the cases, fixed seeds, tolerances from the standard error).
"""

from __future__ import annotations

import math

import mitsuba as mi
import numpy as np
import pytest
from scipy import stats

from phonglab import figures, probe
from phonglab.stats import ALPHA, sidak
from phonglab.physics import radiometry as R

#: Relative accuracy of a sum of float32 BSDF values (eval runs in float32): ~1e-7 per term,
#: a few ulps after summing 3·10⁴ positive terms in float64.
FLOAT32_SUM = 1e-6


# ------------------------------------------------------------------------------ solid angle
def test_whole_sphere_and_hemisphere():
    assert R.solid_angle_cap(math.pi) == pytest.approx(4 * math.pi, rel=1e-15)
    assert R.solid_angle_cap(math.pi / 2) == pytest.approx(2 * math.pi, rel=1e-15)
    assert R.SPHERE_SOLID_ANGLE == 4 * math.pi
    assert R.sphere_quadrature()[1].sum() == pytest.approx(4 * math.pi, rel=1e-13)
    assert R.hemisphere_quadrature()[1].sum() == pytest.approx(2 * math.pi, rel=1e-13)
    # An infinite plane seen from distance 1 covers a hemisphere.
    assert R.solid_angle_rectangle(1e9, 1e9, 1.0) == pytest.approx(2 * math.pi, rel=1e-8)


@pytest.mark.parametrize("d", [10.0, 100.0, 1000.0])
def test_area_over_r_squared_is_the_small_patch_limit(d):
    """Ω_disk = 2π(1 − d/√(d²+r²)) = π r²/d² (1 − 3r²/(4d²) + …), likewise the square:
    relative error of A/R² is O((size/d)²)."""
    r = 1.0
    disk = R.solid_angle_disk(r, d)
    assert disk == pytest.approx(R.solid_angle(math.pi * r * r, d), rel=(r / d) ** 2)
    assert abs(disk / R.solid_angle(math.pi * r * r, d) - 1) > 0.5 * 0.75 * (r / d) ** 2
    square = R.solid_angle_rectangle(1.0, 1.0, d)
    assert square == pytest.approx(R.solid_angle(1.0, d), rel=(1.0 / d) ** 2)


def test_pixel_solid_angles_tile_the_frustum():
    """The pixels of a 30° camera cover the solid angle of its image rectangle at distance 1."""
    half = math.tan(math.radians(15))
    exact = R.solid_angle_rectangle(2 * half, 2 * half, 1.0)
    # Midpoint rule on a smooth integrand: error O(1/res²).
    for res in (64, 256):
        assert R.pixel_solid_angles(res, res, 30.0).sum() == pytest.approx(exact, rel=0.1 / res ** 2)


# ------------------------------------------------------------------------------ flux and radiance
def test_lambertian_emitter_flux_is_pi_L_A():
    assert R.flux_from_radiance(2.0, 3.0) == pytest.approx(math.pi * 6.0, rel=1e-13)
    # An emitter radiating only within 45° of the normal: Φ = π L A sin²45° = half.  The
    # step in cos θ breaks Gauss–Legendre's exactness; the error is at most one node's share,
    # w_max · 2π cos 45° with w_max <= π/(2n) on [0, 1] (the widest node, near the middle).
    n = 200
    half = R.flux_from_radiance(lambda w: (w[:, 2] >= math.cos(math.pi / 4)) * 1.0, 1.0,
                                n_theta=n, n_phi=4)
    bound = math.pi / (2 * n) * 2 * math.pi * math.cos(math.pi / 4)
    assert half == pytest.approx(math.pi / 2, abs=bound)


def test_particle_flux_follows_the_cosine():
    assert R.particle_flux(2.0, 3.0, 0.5, math.pi / 3) == pytest.approx(2 * 3 * 0.5 * 0.5)


def test_radiance_is_constant_along_a_ray():
    r = np.array([0.5, 1.0, 7.0, 100.0])
    p = R.pencil(2.5, 1e-4, 3e-4, 0.2, 1.1, r)
    np.testing.assert_allclose(p.etendue_1, p.etendue_2, rtol=1e-14)
    np.testing.assert_allclose(p.radiance_1, 2.5, rtol=1e-14)
    np.testing.assert_allclose(p.radiance_2, 2.5, rtol=1e-14)
    np.testing.assert_allclose(p.flux * r ** 2, p.flux[0] * r[0] ** 2, rtol=1e-14)   # 1/r²


# ------------------------------------------------------------------------------ reflection equation
@pytest.mark.parametrize("theta_deg", [0, 30, 60, 85])
def test_lambert_reflects_rho_times_a_uniform_sky(variant_llvm_rgb, theta_deg):
    bsdf = R_bsdf("lambert", reflectance=0.7)
    value = R.reflected_radiance(bsdf, probe.direction(math.radians(theta_deg)), incident=2.0)
    np.testing.assert_allclose(value, 1.4, rtol=FLOAT32_SUM)


@pytest.mark.parametrize("p", [0, 1, 10, 100])
def test_phong_albedo_at_normal_incidence_is_kd_plus_ks(variant_llvm_rgb, p):
    """Each lobe integrates to its reflectance when it lies entirely above the horizon
    (plugins/phong.py docstring): a(0) = k_d + k_s."""
    bsdf = R_bsdf("phong", diffuse_reflectance=0.5, specular_reflectance=0.3, exponent=float(p))
    np.testing.assert_allclose(R.reflected_radiance(bsdf, [0.0, 0.0, 1.0]), 0.8, rtol=FLOAT32_SUM)


def test_reflection_equation_with_a_cosine_sky(variant_llvm_rgb):
    """Lambert under L_i = cos θ_i: L_r = ρ/π ∫ cos²θ dω = ρ/π · 2π/3 = 2ρ/3, for any view."""
    bsdf = R_bsdf("lambert", reflectance=0.6)
    views = probe.direction([0.0, 0.7, 1.3])
    out = R.reflected_radiance(bsdf, views, lambda w: w[:, 2])
    assert out.shape == (3, 3)
    np.testing.assert_allclose(out, 0.4, rtol=FLOAT32_SUM)


def R_bsdf(kind, **params):
    return mi.load_dict({"type": kind, **params})


# ------------------------------------------------------------------------------ Monte Carlo
CASES = [(p, t) for p in (0.0, 10.0, 100.0) for t in (0.0, 60.0)]


@pytest.mark.parametrize("p, theta_deg", CASES, ids=[f"p{p:g}-{t:g}deg" for p, t in CASES])
def test_mean_sample_weight_is_the_albedo(variant_llvm_rgb, p, theta_deg):
    """E[f_r cos θ_o / pdf] = a(θ) (the quadrature value, exact to ~1e-6 by the tests above):
    z-test on 50 000 samples at ALPHA, Šidák over the cases."""
    bsdf = R_bsdf("phong", diffuse_reflectance=0.5, specular_reflectance=0.3, exponent=p)
    wi = probe.direction(math.radians(theta_deg))
    expected = R.reflected_radiance(bsdf, wi)[0]
    est = R.directional_albedo(bsdf, wi, n=50_000, seed=int(p) * 100 + int(theta_deg))
    z = (est.mean[0] - expected) / est.stderr[0]
    assert 2 * stats.norm.sf(abs(z)) > sidak(ALPHA, len(CASES)), (est.mean[0], expected, z)


def test_furnace_render_is_the_albedo(variant_llvm_rgb):
    """nb_furnace_sphere.xml: each sphere pixel's expected value is the pixel-area average of
    a(θ), θ = asin r (orthographic view of a unit sphere, image extent ±1.1, box filter).
    Pixels with r < 0.9 (away from the silhouette): z = Σ(pixel − a) / √Σ s.e.², the
    standard errors from 8 independent passes (thousands of pixels: the pooled variance is
    accurate), two-sided at ALPHA."""
    kd, ks, p, res, extent = 0.5, 0.3, 10.0, 64, 1.1
    result = figures.render_furnace(spp=64, passes=8, res=res, kd=kd, ks=ks, exponent=p)
    bsdf = R_bsdf("phong", diffuse_reflectance=kd, specular_reflectance=ks, exponent=p)
    # a(θ) tabulated finely in θ (linear interpolation error ~ Δθ²/8 · |a''| < 1e-5).
    grid = np.linspace(0.0, math.asin(0.95), 240)
    table = R.reflected_radiance(bsdf, probe.direction(grid),
                                 n_theta=96, n_phi=192)[:, 0]
    sub = 4                                              # 4 x 4 sub-pixel average
    c = ((np.arange(res * sub) + 0.5) / (res * sub) * 2 - 1) * extent
    xx, yy = np.meshgrid(c, c)
    r = np.hypot(xx, yy)
    a_sub = np.interp(np.arcsin(np.minimum(r, 0.95)), grid, table)
    a_pix = a_sub.reshape(res, sub, res, sub).mean(axis=(1, 3))
    r_max = r.reshape(res, sub, res, sub).max(axis=(1, 3))
    mask = r_max < 0.9
    img, se = result.image[..., 0], result.stderr[..., 0]
    diff = img[mask] - a_pix[mask]
    z = diff.sum() / math.sqrt(np.sum(se[mask] ** 2))
    assert mask.sum() > 2000
    print(f"furnace: z = {z:+.3f}, mean(pixel - a) = {diff.mean():+.2e} over {mask.sum()} pixels")
    assert 2 * stats.norm.sf(abs(z)) > ALPHA, (z, diff.mean())
