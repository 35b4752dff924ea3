r"""Monte Carlo convergence: RMSE falls as N^−½, inside the band its variance predicts.

Estimators (:mod:`phonglab.estimators`).  For S independent estimates X̄_s with N
samples each, of an integrand whose per-sample value has variance σ² and excess
kurtosis γ₂, the mean squared error over the seeds M_N = (1/S) Σ (X̄_s − μ)² has

    E[M_N] = σ²/N,   Var[M_N] = (σ²/N)² (2 + γ₂/N) / S

(a mean of N samples has excess kurtosis γ₂/N).  Matching these two moments with a
scaled χ² (Satterthwaite) gives  M_N ν N/σ² ~ χ²_ν,  ν = 2S/(2 + γ₂/N), so the band

    σ/√N · √(χ²_ν(a/2)/ν) ≤ RMSE_N ≤ σ/√N · √(χ²_ν(1 − a/2)/ν)

holds with probability 1 − a; a = sidak(ALPHA, all band checks).  μ is the exact
value from quadrature, so the band also tests unbiasedness.  σ² and γ₂ come from
an independent run of n_ref = 2²² samples (for MIS, X is one pair's value and the
N-sample estimate averages N/2 pairs: N → N/2 above); σ̂²'s own relative standard deviation
√((2 + γ₂)/n_ref) widens the band by z_a times that on each side.

The slope of log RMSE_N against log N (ordinary least squares, N = 2⁸ … 2¹⁶) must
lie in [−0.55, −0.45].  By the delta method Var[log RMSE_N] ≈ (2 + γ₂/N)/(4S);
each case takes the smallest S (a power of two) for which z_a · SE(slope) ≤ 0.05, so a
correct estimator fails the slope check with probability below a.

Zero-variance cases (cosine-weighted or BSDF sampling of a Lambertian BSDF under a
constant light: eval/pdf = ρ for every sample) are recognised by
:attr:`Estimate.is_zero_variance` and asserted exact.

Renders: RMSE of Cornell-box renders against a high-sample reference (cached under
``.bench_cache/``, generated on first use) falls as spp^−½.  The reference's own
variance (its per-pixel standard error², measured from its passes) is subtracted
from the MSE, so the fit sees σ²/spp alone.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from phonglab.bench import CornellSpec
from phonglab.engine.metrics import errors
from phonglab.physics.estimators import Problem, ReflectionEstimators, exact_value
from phonglab.engine.render import render_scene
from phonglab.stats import ALPHA, sidak

N_LIST = [2 ** k for k in range(8, 17)]
SLOPE_RANGE = (-0.55, -0.45)
N_REF = 1 << 22

_CONST = dict(bsdf="phong", diffuse_reflectance=0.5, specular_reflectance=0.3, exponent=30.0,
              theta_i=30.0, light="constant")
_DISK = dict(bsdf="phong", diffuse_reflectance=0.0, specular_reflectance=1.0, exponent=100.0,
             theta_i=45.0, light="disk", half_angle=10.0)
_LAMBERT_DISK = dict(bsdf="lambert", diffuse_reflectance=0.7, theta_i=60.0, light="disk",
                     half_angle=10.0)

#: Finite-variance cases: (id, problem, method).
CASES = [(f"const-{m}", _CONST, m) for m in ("uniform", "cosine", "bsdf", "light", "mis")] + \
        [(f"disk-{m}", _DISK, m) for m in ("uniform", "cosine", "bsdf", "light", "mis")] + \
        [("lambert-disk-light", _LAMBERT_DISK, "light"), ("lambert-disk-mis", _LAMBERT_DISK, "mis")]

A_BAND = sidak(ALPHA, len(CASES) * len(N_LIST))
A_SLOPE = sidak(ALPHA, len(CASES))


def _slope_se(sigma_rel_var: np.ndarray) -> float:
    """SE of the OLS slope of log RMSE on log N given Var[log RMSE_N] per point."""
    x = np.log(np.array(N_LIST, float))
    c = (x - x.mean()) / np.sum((x - x.mean()) ** 2)
    return float(math.sqrt(np.sum(c * c * sigma_rel_var)))


def _design_seeds(gamma2: float, z: float) -> int:
    """Smallest S = 2^k >= 64 with z · SE(slope) <= 0.05 (Var log RMSE = (2 + γ₂/N)/(4S))."""
    per_point = np.array([(2.0 + gamma2 / (n // 2)) / 4.0 for n in N_LIST])  # MIS's pairs: worst case
    s = 64
    while z * _slope_se(per_point / s) > 0.05 and s < 8192:
        s *= 2
    return s


@pytest.fixture
def estimators(variant_llvm_rgb):
    return ReflectionEstimators(Problem(**_CONST))


@pytest.mark.parametrize("case_id,problem,method", CASES, ids=[c[0] for c in CASES])
def test_rmse_converges_as_inverse_sqrt_n(estimators, case_id, problem, method):
    est = estimators.set(Problem(**problem))
    mu = exact_value(est.problem)
    _, sigma2, gamma2 = est.moments(method, N_REF, seed=0xC0FFEE)
    gamma2 = max(gamma2, 0.0)
    assert sigma2 > 0, f"{case_id}: expected a finite, non-zero variance"
    z_slope = stats.norm.isf(A_SLOPE / 2)
    seeds = _design_seeds(gamma2, z_slope)
    z_band = stats.norm.isf(A_BAND / 2)
    widen = z_band * math.sqrt((2.0 + gamma2) / N_REF)   # relative uncertainty of σ̂²
    rmse, lo, hi = [], [], []
    for k, n in enumerate(N_LIST):
        e = est.run(method, n, seed=1000 + 17 * k, batches=seeds)
        assert e.nan_count == 0 and e.inf_count == 0, f"{case_id}: non-finite samples at N={n}"
        rmse.append(math.sqrt(np.mean((e.values - mu) ** 2)))
        m = n // 2 if method == "mis" else n     # independent terms of the mean (MIS: pairs)
        nu = 2.0 * seeds / (2.0 + gamma2 / m)
        scale = sigma2 / m
        lo.append(math.sqrt(scale * (1 - widen) * stats.chi2.ppf(A_BAND / 2, nu) / nu))
        hi.append(math.sqrt(scale * (1 + widen) * stats.chi2.isf(A_BAND / 2, nu) / nu))
    rmse, lo, hi = map(np.array, (rmse, lo, hi))
    table = "\n".join(f"  N={n:6d} RMSE={r:.4g} band=[{a:.4g}, {b:.4g}]"
                      for n, r, a, b in zip(N_LIST, rmse, lo, hi))
    slope = np.polyfit(np.log(N_LIST), np.log(rmse), 1)[0]
    detail = (f"{case_id} ({est.problem.label}, {method}): exact {mu:.6g}, σ²={sigma2:.4g}, "
              f"γ₂={gamma2:.3g}, S={seeds} seeds, slope {slope:.4f}\n{table}")
    outside = (rmse < lo) | (rmse > hi)
    assert not outside.any(), f"RMSE outside its predicted band:\n{detail}"
    assert SLOPE_RANGE[0] <= slope <= SLOPE_RANGE[1], f"slope out of range:\n{detail}"


ZERO_VARIANCE = [
    ("lambert-cosine", dict(bsdf="lambert", diffuse_reflectance=0.7, light="constant"), "cosine"),
    ("lambert-bsdf", dict(bsdf="lambert", diffuse_reflectance=0.7, light="constant"), "bsdf"),
    ("diffuse-bsdf", dict(bsdf="diffuse", diffuse_reflectance=0.7, light="constant"), "bsdf"),
]


@pytest.mark.parametrize("theta_i", [0.0, 60.0, 89.9])
@pytest.mark.parametrize("case_id,problem,method", ZERO_VARIANCE, ids=[c[0] for c in ZERO_VARIANCE])
def test_zero_variance_cases_are_exact(estimators, case_id, problem, method, theta_i):
    """Cosine/BSDF sampling of f = ρ/π under L ≡ 1: X = (ρ/π cos θ)/(cos θ/π) = ρ for every sample."""
    est = estimators.set(Problem(theta_i=theta_i, **problem))
    rho = float(np.float32(0.7))
    e = est.run(method, 1 << 12, seed=3, batches=4)
    assert e.is_zero_variance, f"{case_id}: sample variance {e.sample_variance:g} is not zero"
    # Cosine sampling divides (ρ/π cos θ) by (cos θ/π) in float32: exact up to a few ulp.
    assert np.all(np.abs(e.values - rho) <= 4 * 2.0 ** -24 * rho), e.values
    assert np.all(e.stderr <= 4 * 2.0 ** -24 * rho), e.stderr
    if method == "bsdf":
        assert np.all(e.values == rho) and np.all(e.stderr == 0.0)


def test_finite_variance_case_is_not_flagged_zero_variance(estimators):
    est = estimators.set(Problem(bsdf="lambert", diffuse_reflectance=0.7, light="constant"))
    assert not est.run("uniform", 1 << 12, seed=3).is_zero_variance


# ---------------------------------------------------------------------------------------------
# Full renders: the Cornell box against a cached high-sample reference
# ---------------------------------------------------------------------------------------------

RENDER_SPPS = [2, 4, 8, 16, 32, 64, 128]
#: Renders per spp.  One render's MSE is heavy-tailed (relative SD ≈ 0.55 at 24-32 px: a few
#: bright paths dominate), so with 4 seeds the slope scattered by ≈ 0.05 (a third of seed
#: sets fell outside the band, for any seeding); 32 seeds bring it to ≈ 0.017 (measured over
#: 8 seed sets), 3 SD inside [−0.55, −0.45].
RENDER_SEEDS = 32
RENDER_REF_SPP = 4096


def _render_slope(spec, spps, seeds, ref_spp):
    """OLS slope of log RMSE on log spp, the RMSE table, and the reference noise level."""
    ref = spec.reference(ref_spp, "llvm_ad_rgb")
    ref_err = ref.stderr
    scene = spec.load("llvm_ad_rgb")
    rmse = []
    for spp in spps:
        mse = [errors(render_scene(scene, spp, seed=7919 * spp + s).image, ref.image, ref_err)["mse"]
               for s in range(seeds)]
        rmse.append(math.sqrt(max(float(np.mean(mse)), 1e-30)))
    slope = np.polyfit(np.log(spps), np.log(rmse), 1)[0]
    return slope, rmse, float(np.sqrt(np.mean(ref_err ** 2)))


RENDER_CASES = [("lambert+phong", "lambert", "phong"), ("diffuse+roughplastic", "diffuse", "roughplastic")]


@pytest.mark.parametrize("case_id,walls,boxes", RENDER_CASES, ids=[c[0] for c in RENDER_CASES])
def test_render_rmse_falls_as_inverse_sqrt_spp(variant_llvm_rgb, case_id, walls, boxes):
    """Cornell box, 24 px, box filter: RMSE(spp) against a 4096-spp reference ∝ spp^−½.

    The reference's own variance (per-pixel stderr² from its 16 passes) is subtracted from
    each MSE, so only σ²/spp remains; the box filter makes every pixel a plain mean (see
    :func:`phonglab.bench.cornell_xml`).  Each RMSE averages 24·24·3 pixel values and
    :data:`RENDER_SEEDS` renders, so the slope's scatter is ≈ 0.017, 3 SD inside [−0.55, −0.45].
    """
    spec = CornellSpec(walls=walls, boxes=boxes, res=24)
    slope, rmse, ref_noise = _render_slope(spec, RENDER_SPPS, RENDER_SEEDS, RENDER_REF_SPP)
    table = ", ".join(f"{s}:{r:.4g}" for s, r in zip(RENDER_SPPS, rmse))
    assert SLOPE_RANGE[0] <= slope <= SLOPE_RANGE[1], \
        f"{case_id}: slope {slope:.4f}; RMSE by spp {table}; reference noise {ref_noise:.3g}"
    assert rmse[-1] > 3 * ref_noise, "the reference is too noisy to measure the largest spp"


@pytest.mark.slow
@pytest.mark.parametrize("walls,boxes", [("lambert", "lambert"), ("diffuse", "diffuse"),
                                         ("diffuse", "phong"), ("diffuse", "plastic"),
                                         ("diffuse", "roughplastic")])
def test_render_rmse_slope_every_bsdf_64px(variant_llvm_rgb, walls, boxes):
    """The same at 64 px, spp 4–512 against a 16384-spp reference, for every compared BSDF."""
    spec = CornellSpec(walls=walls, boxes=boxes, res=64)
    spps = [4, 8, 16, 32, 64, 128, 256, 512]
    slope, rmse, ref_noise = _render_slope(spec, spps, 2, 16384)
    table = ", ".join(f"{s}:{r:.4g}" for s, r in zip(spps, rmse))
    assert SLOPE_RANGE[0] <= slope <= SLOPE_RANGE[1], f"{walls}/{boxes}: slope {slope:.4f}; {table}"


# ---------------------------------------------------------------------------------------------
# mis_optimal: a two-stage estimator (pilot, then an allocation and weights chosen from it)
# ---------------------------------------------------------------------------------------------

#: (id, problem): phonglab's convergence problems, a lobe partly below the horizon (rejected
#: BSDF samples: the null point), a lobe inside the light (BSDF sampling alone is near
#: exact) and a wide lobe under a small light (light sampling alone is near exact).
OPTIMAL_CASES = [
    ("const", _CONST), ("disk", _DISK), ("lambert-disk", _LAMBERT_DISK),
    ("horizon", dict(bsdf="phong", diffuse_reflectance=0.2, specular_reflectance=0.8,
                     exponent=10.0, theta_i=80.0, light="constant")),
    ("lobe-in-light", dict(bsdf="phong", diffuse_reflectance=0.0, specular_reflectance=1.0,
                           exponent=1e5, theta_i=30.0, light="disk", half_angle=1.0)),
    ("light-in-lobe", dict(bsdf="phong", diffuse_reflectance=0.0, specular_reflectance=1.0,
                           exponent=10.0, theta_i=30.0, light="disk", half_angle=1.0)),
]
OPTIMAL_N, OPTIMAL_S = 4096, 256
#: Two checks per case (bias, standard error), Šidák over all of them.
A_OPTIMAL = sidak(ALPHA, 2 * len(OPTIMAL_CASES))


@pytest.mark.parametrize("case_id,problem", OPTIMAL_CASES, ids=[c[0] for c in OPTIMAL_CASES])
def test_mis_optimal_is_unbiased_and_its_standard_error_is_calibrated(estimators, case_id, problem):
    """S = 256 estimates of N = 4096 samples against the quadrature value μ.

    Unbiased: z = (mean − μ)/√(mean(stderr²)/S) is standard normal (the pilot is independent of
    the samples it weights).  Calibrated: (S − 1) · var(estimates)/mean(stderr²) ~ χ²_{S−1}
    (the stratified stderr² estimates each estimate's variance to ~√(2/N), far inside the band).
    Near-zero-variance cases may sit at float32 rounding of μ: a floor of 8 ulp of μ.
    """
    est = estimators.set(Problem(**problem))
    mu = exact_value(est.problem)
    e = est.run("mis_optimal", OPTIMAL_N, seed=4242, batches=OPTIMAL_S)
    assert e.nan_count == 0 and e.inf_count == 0
    se2 = float(np.mean(e.stderr ** 2))
    se_mean = math.sqrt(se2 / OPTIMAL_S)
    z = stats.norm.isf(A_OPTIMAL / 2)
    err = float(np.mean(e.values)) - mu
    assert abs(err) <= z * se_mean + 8 * 2.0 ** -24 * abs(mu), \
        f"{case_id}: mean {np.mean(e.values):.8g} vs exact {mu:.8g}, SE {se_mean:.3g}"
    if se2 > (8 * 2.0 ** -24 * abs(mu)) ** 2:
        stat = (OPTIMAL_S - 1) * float(np.var(e.values, ddof=1)) / se2
        lo, hi = stats.chi2.ppf(A_OPTIMAL / 2, OPTIMAL_S - 1), stats.chi2.isf(A_OPTIMAL / 2, OPTIMAL_S - 1)
        assert lo <= stat <= hi, f"{case_id}: (S−1)·var/stderr² = {stat:.1f} outside [{lo:.1f}, {hi:.1f}]"


#: Stability-map cells (pure-specular phong, N = 2^14 as in the bench): where BSDF sampling
#: wins, where light sampling wins, and where both are comparable.
TARGET_CELLS = [dict(light="constant", exponent=10.0, theta_i=0.0),
                dict(light="constant", exponent=1e5, theta_i=30.0),
                dict(light="disk", half_angle=1.0, exponent=0.0, theta_i=30.0),
                dict(light="disk", half_angle=1.0, exponent=1e3, theta_i=80.0),
                dict(light="disk", half_angle=1.0, exponent=1e4, theta_i=30.0)]


@pytest.mark.parametrize("cell", TARGET_CELLS, ids=[f"{c['light']}-p{c['exponent']:g}-t{c['theta_i']:g}"
                                                    for c in TARGET_CELLS])
def test_mis_optimal_variance_is_near_the_better_strategy_and_below_power_mis(estimators, cell):
    """At equal sample count N = 2^14: σ²(mis_optimal) ≤ 1.2² · min(σ²_bsdf, σ²_light) and
    ≤ σ²(power-heuristic mis), σ² = N · mean(stderr²) over S = 16 estimates.

    The expected ratio to the better strategy is 32/31 (the discarded pilot) where one strategy
    dominates and below 1 where the optimal weights beat both; each σ² estimate pools 2^18
    samples, so its own relative error (~√((2 + γ₂)/2^18), a few % even for γ₂ ~ 10³) stays far
    inside the 1.44 margin.
    """
    est = estimators.set(Problem(bsdf="phong", diffuse_reflectance=0.0, specular_reflectance=1.0,
                                 **cell))
    n = 1 << 14
    var = {m: n * float(np.mean(est.run(m, n, seed=77, batches=16).stderr ** 2))
           for m in ("bsdf", "light", "mis", "mis_optimal")}
    best = min(var["bsdf"], var["light"])
    assert var["mis_optimal"] <= 1.2 ** 2 * best, var
    assert var["mis_optimal"] <= var["mis"], var
