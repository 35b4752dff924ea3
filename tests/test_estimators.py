"""phonglab.physics.estimators: exact values (closed forms, quadrature convergence, an independent
2-D quadrature), input errors, and sweeps that never recompile.  Cheap checks only; the
statistical convergence of the estimators is in test_convergence.py."""

from __future__ import annotations

import math

import numpy as np
import pytest

from phonglab.errors import PhonglabError
from phonglab.physics.estimators import (ALLOCATIONS, METHODS, Problem, ReflectionEstimators,
                                         choose_allocation, clipped_cosine_mean,
                                         exact_normal_incidence, exact_value)


@pytest.mark.parametrize("A,B", [(0.3, 0.0), (-0.2, 0.0), (0.5, 0.2), (0.1, 0.7), (-0.3, 0.6),
                                 (-0.7, 0.2), (0.0, 1.0)])
def test_clipped_cosine_mean_matches_numeric_integral(A, B):
    """h(A, B) = (1/2π)∫ max(0, A + B cos φ) dφ against a 200 000-point midpoint rule."""
    phi = (np.arange(200_000) + 0.5) * (2 * np.pi / 200_000)
    numeric = np.mean(np.maximum(0.0, A + B * np.cos(phi)))
    assert clipped_cosine_mean(A, B) == pytest.approx(numeric, abs=1e-9)


CLOSED = [dict(bsdf="phong", diffuse_reflectance=kd, specular_reflectance=ks, exponent=p,
               light=light, half_angle=d, theta_i=0.0)
          for kd, ks in ((0.0, 1.0), (0.5, 0.3)) for p in (0.0, 1.0, 30.0, 1e3, 1e5)
          for light, d in (("constant", 3.0), ("disk", 1.0), ("disk", 10.0))] + \
         [dict(bsdf="lambert", diffuse_reflectance=0.7, light=light, half_angle=5.0, theta_i=0.0)
          for light in ("constant", "disk")]


@pytest.mark.parametrize("kw", CLOSED, ids=lambda kw: "-".join(f"{v}" for v in kw.values()))
def test_exact_value_matches_closed_form_at_normal_incidence(kw):
    """θ_i = 0: disk k_d L_e sin²δ + k_s L_e (1 − cos^{p+2} δ); constant light k_d + k_s.

    The quadrature uses the float32-rounded cos δ that the kernel sees; the closed form the
    exact one, so they agree to that rounding (|Δ(1 − cos δ)| <= 2⁻²⁴ relative to 1).
    """
    pr = Problem(**kw)
    tol = 1e-12 if pr.light == "constant" else 4 * 2.0 ** -24 * (pr.exponent + 2) + 1e-12
    assert exact_value(pr) == pytest.approx(exact_normal_incidence(pr), rel=1e-8, abs=tol)


@pytest.mark.parametrize("p", [0.0, 10.0, 1e3, 1e5])
@pytest.mark.parametrize("theta", [45.0, 89.9])
@pytest.mark.parametrize("light", ["constant", "disk"])
def test_exact_quadrature_is_converged(p, theta, light):
    """Doubling the panels changes the value by < 10⁻⁸ relative (the kink at the horizon included)."""
    pr = Problem(exponent=p, theta_i=theta, light=light, half_angle=3.0, diffuse_reflectance=0.2,
                 specular_reflectance=0.7)
    a, b = exact_value(pr), exact_value(pr, panels=512)
    assert a > 0 and abs(a - b) <= 1e-8 * a


def test_exact_value_agrees_with_independent_2d_quadrature():
    """The reduction to h(A, B) against brute force: a midpoint grid over the cone around R,
    evaluating f_r cos θ_o = (k_d/π + k_s (p+2)/(2π) cos^p α) max(0, ω_o·N) directly."""
    kd, ks, p, theta, delta = 0.3, 0.5, 10.0, 60.0, 25.0
    pr = Problem(diffuse_reflectance=kd, specular_reflectance=ks, exponent=p, theta_i=theta,
                 light="disk", half_angle=delta)
    t = math.radians(theta)
    R = np.array([-math.sin(t), 0.0, math.cos(t)])
    e1 = np.array([math.cos(t), 0.0, math.sin(t)])   # ⟂ R, in the plane of R and N
    e2 = np.cross(R, e1)
    n_g, n_p = 2000, 2000
    cos_d = float(np.float32(math.cos(math.radians(delta))))
    c = cos_d + (1 - cos_d) * (np.arange(n_g) + 0.5) / n_g      # uniform in cos γ: dω = dc dφ
    phi = (np.arange(n_p) + 0.5) * 2 * np.pi / n_p
    C, PHI = np.meshgrid(c, phi, indexing="ij")
    S = np.sqrt(1 - C * C)
    wo = C[..., None] * R + S[..., None] * (np.cos(PHI)[..., None] * e1 + np.sin(PHI)[..., None] * e2)
    cos_o = np.maximum(0.0, wo[..., 2])
    f = kd / np.pi + ks * (p + 2) / (2 * np.pi) * np.maximum(0.0, C) ** p   # α = γ: cone axis = R
    brute = np.sum(f * cos_o) * (1 - cos_d) / n_g * 2 * np.pi / n_p
    assert exact_value(pr) == pytest.approx(brute, rel=2e-5)


@pytest.mark.parametrize("kw,match", [
    (dict(theta_i=90.0), "theta_i"), (dict(theta_i=-1.0), "theta_i"),
    (dict(light="sun"), "light"), (dict(exponent=-1.0), "exponent"),
    (dict(exponent=float("inf")), "exponent"), (dict(half_angle=0.0), "half_angle"),
])
def test_bad_problems_are_clear_errors(kw, match):
    with pytest.raises(PhonglabError, match=match):
        Problem(**kw)


def test_exact_value_refuses_unknown_bsdf():
    with pytest.raises(PhonglabError, match="no exact value"):
        exact_value(Problem(bsdf="roughplastic"))


def test_bad_estimator_calls_are_clear_errors(variant_llvm_rgb):
    est = ReflectionEstimators(Problem())
    with pytest.raises(PhonglabError, match="unknown estimator"):
        est.run("stratified", 64)
    with pytest.raises(PhonglabError, match="n >= 2"):
        est.run("bsdf", 1)
    with pytest.raises(PhonglabError, match="mis_optimal needs n >= 64"):
        est.run("mis_optimal", 32)


def _pilot_rows(rng, f_of, m=512):
    """A synthetic pilot on [0, 1]: p_b(x) = 2x, p_l(x) = 1 (M/2 samples of each), f = f_of(x)."""
    xb = np.sqrt(rng.random((4, m // 2)))          # inverse CDF of p_b = 2x
    xl = rng.random((4, m // 2))
    x = np.concatenate([xb, xl], axis=1)
    return f_of(x), 2.0 * x, np.ones_like(x)


def test_choose_allocation_solves_the_2x2_system_exactly_for_a_mixture_of_the_pdfs():
    """f = 3 p_b + 0.5 p_l is its own control variate: α = (3, 0.5) and σ²(c) = 0 for every
    mixture, while either strategy alone has σ² > 0 (f/p_b, f/p_l are not constant)."""
    fv, pb, pl = _pilot_rows(np.random.default_rng(1), lambda x: 3.0 * 2.0 * x + 0.5)
    c_b, a_b, a_l, s2 = choose_allocation(fv, pb, pl, allocations=(0.5,))
    np.testing.assert_allclose(a_b, 3.0, rtol=1e-9)
    np.testing.assert_allclose(a_l, 0.5, rtol=1e-9)
    np.testing.assert_allclose(s2, 0.0, atol=1e-9)
    c_b, _, _, s2 = choose_allocation(fv, pb, pl)
    assert np.all((c_b > 0.0) & (c_b < 1.0)) and np.all(s2 == 0.0)
    for end in (0.0, 1.0):
        assert np.all(choose_allocation(fv, pb, pl, allocations=(end,))[3] > 0.1)


def test_choose_allocation_matches_the_analytic_variance_of_each_pure_strategy():
    """f(x) = x on [0, 1] (μ = 1/2): light sampling (p_l = 1) has σ² = 1/3 − 1/4 = 1/12,
    BSDF sampling (p_b = 2x) has f/p_b = 1/2, σ² = 0: the pilot picks c_b = 1."""
    fv, pb, pl = _pilot_rows(np.random.default_rng(2), lambda x: x, m=1 << 14)
    _, _, _, s2_l = choose_allocation(fv, pb, pl, allocations=(0.0,))
    # Var of the pilot estimate of E_q[x²/(p_l q)]: a loose 5 % (M = 16384, tail bounded).
    np.testing.assert_allclose(s2_l, 1.0 / 12.0, rtol=0.05)
    c_b, a_b, a_l, s2 = choose_allocation(fv, pb, pl)
    assert np.all(c_b == 1.0) and np.all(a_l == 0.0)
    np.testing.assert_allclose(s2, 0.0, atol=1e-12)


def test_choose_allocation_refuses_a_pure_strategy_that_misses_part_of_f():
    """f > 0 where p_b = 0: BSDF sampling alone would be biased, so σ²(c_b = 1) = ∞."""
    fv, pb, pl = _pilot_rows(np.random.default_rng(3), lambda x: np.ones_like(x))
    pb[:, -1] = 0.0
    _, _, _, s2 = choose_allocation(fv, pb, pl, allocations=(1.0,))
    assert np.all(np.isinf(s2))
    c_b, *_ = choose_allocation(fv, pb, pl)
    assert np.all(c_b < 1.0) and len(ALLOCATIONS) > 2


def test_mis_optimal_main_stage_counts_nan_and_inf_only_when_a_sum_is_not_finite(variant_llvm_rgb):
    """The main stage sums four numbers a row; a row whose α is NaN (Inf) makes every residual
    NaN (−Inf) there, and the counting kernel must then find exactly ``per`` of them in that
    row and none in the healthy one (whose sums stay finite)."""
    import drjit as dr
    import mitsuba as mi
    from phonglab.physics.estimators.optimal_mis import optimal_sums

    est = ReflectionEstimators(Problem(exponent=30.0, theta_i=30.0, half_angle=5.0))
    per, rows = 512, 3
    n_b = mi.UInt32([per, per, per // 2, per // 2])          # row 0, 1: BSDF only (c·p > 0)
    alpha_b = mi.Float([float("nan"), float("inf"), 0.0, 0.0])
    alpha_l = mi.Float([0.0, 0.0, 0.0, 0.0])
    dr.eval(n_b, alpha_b, alpha_l)
    t = optimal_sums(est.integrand, per, rows, n_b, alpha_b, alpha_l, seed=3)
    assert list(t["nan"]) == [per, 0, 0] and list(t["inf"]) == [0, per, 0]
    assert np.isfinite([t[k][2] for k in ("sum_b", "sum", "sq_b", "sq")]).all()
    healthy = est.run("mis_optimal", 4096, seed=5, batches=2)
    assert healthy.nan_count == 0 and healthy.inf_count == 0 and np.isfinite(healthy.values).all()


def test_mis_optimal_frozen_replay_matches_a_fresh_trace_as_the_problem_changes(variant_llvm_rgb):
    """``mis_optimal`` replays a recording (dr.freeze): every input that a sweep changes (the
    exponent inside the plugin, ω_i, the light's axis, size and radiance, the seed, the
    material) must reach the replayed kernels, so each replay agrees with a fresh trace of the
    same seeds and not with the problem recorded first."""
    from phonglab.physics.estimators.optimal_mis import FROZEN, run_optimal

    est = ReflectionEstimators(Problem(exponent=10.0, theta_i=30.0, half_angle=3.0))
    seen = []
    for change in (dict(), dict(exponent=1e3, theta_i=60.0), dict(half_angle=10.0, radiance=2.0),
                   dict(exponent=0.0, theta_i=80.0, light="constant"), dict(seed=9),
                   dict(bsdf="lambert", diffuse_reflectance=0.4)):
        seed = change.pop("seed", 4)
        est.set(**change)
        frozen = run_optimal(est.integrand, 2048, 4, seed, est.CHUNK, frozen=True)
        fresh = run_optimal(est.integrand, 2048, 4, seed, est.CHUNK, frozen=False)
        np.testing.assert_allclose(frozen[0], fresh[0], rtol=1e-6, err_msg=str(change))
        np.testing.assert_allclose(frozen[1], fresh[1], rtol=1e-5, err_msg=str(change))
        seen.append(float(np.mean(frozen[0])))
    assert len(set(seen)) == len(seen), seen                   # no replay returned a stale value
    assert FROZEN.n_recordings >= 1


def test_sweeping_exponent_angle_and_light_size_never_recompiles(variant_llvm_rgb):
    """Opaque parameters: a sweep launches the kernels of its first point, by hash."""
    est = ReflectionEstimators(Problem(exponent=10.0, theta_i=30.0, half_angle=3.0))
    first = {m: est.run(m, 256, seed=1).kernel_hashes for m in METHODS}
    # One kernel per estimator; mis_optimal launches three, back to back on the device: its
    # pilot, the 2×2 solves (one lane per estimate) and its main stage.
    assert all(len(h) == (3 if m == "mis_optimal" else 1) for m, h in first.items()), first
    for p, theta, delta in ((1e4, 80.0, 1.0), (0.0, 0.0, 10.0), (1e5, 89.9, 0.5)):
        est.set(exponent=p, theta_i=theta, half_angle=delta, radiance=2.0)
        for m in METHODS:
            e = est.run(m, 512, seed=7, batches=3)
            assert e.kernel_hashes == first[m], f"{m} recompiled at p={p}, θ={theta}, δ={delta}"


def test_estimates_scale_with_radiance(variant_llvm_rgb):
    """L_r is linear in L_e: same seed, twice the radiance, exactly twice the estimate."""
    est = ReflectionEstimators(Problem(exponent=30.0, theta_i=40.0, light="disk", half_angle=5.0))
    for m in METHODS:
        a = est.set(radiance=1.0).run(m, 1024, seed=3).value
        b = est.set(radiance=2.0).run(m, 1024, seed=3).value
        assert b == pytest.approx(2 * a, rel=1e-6)
    assert est.exact() == pytest.approx(2 * est.set(radiance=1.0).exact(), rel=1e-12)
