"""The `lambert` and `phong` plugins, cheapest checks first (after mitsuba3's test_diffuse.py).

create/flags -> eval against the closed form -> eval/pdf consistency -> weight == eval/pdf
-> reciprocity -> finite at grazing angles and extreme exponents -> chi^2 of the sampling
-> white furnace (directional albedo) with tolerances from the Monte Carlo standard error.
"""

from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from scipy import stats

from phonglab import probe
from phonglab.physics import radiometry
from phonglab.stats import ALPHA, sidak

# name -> (plugin type, parameters); parameters as numbers (gray) or RGB triples.
CASES = {
    "lambert-gray": ("lambert", {"reflectance": 0.5}),
    "lambert-rgb": ("lambert", {"reflectance": [0.2, 0.5, 0.8]}),
    "phong-p0": ("phong", {"diffuse_reflectance": 0.3, "specular_reflectance": 0.6, "exponent": 0.0}),
    "phong-p1": ("phong", {"diffuse_reflectance": 0.5, "specular_reflectance": 0.5, "exponent": 1.0}),
    "phong-default": ("phong", {}),
    "phong-rgb-p25": ("phong", {"diffuse_reflectance": [0.6, 0.3, 0.2], "specular_reflectance": 0.2,
                                "exponent": 25.0}),
    "phong-specular-p100": ("phong", {"diffuse_reflectance": 0.0, "specular_reflectance": 1.0,
                                      "exponent": 100.0}),
    "phong-p1000": ("phong", {"diffuse_reflectance": 0.1, "specular_reflectance": 0.9, "exponent": 1e3}),
    "phong-p1e5": ("phong", {"diffuse_reflectance": 0.1, "specular_reflectance": 0.9, "exponent": 1e5}),
    "phong-diffuse-only": ("phong", {"diffuse_reflectance": 1.0, "specular_reflectance": 0.0}),
}
DEFAULTS = {"lambert": {"reflectance": 0.5},
            "phong": {"diffuse_reflectance": 0.5, "specular_reflectance": 0.2, "exponent": 30.0}}


def params_of(case):
    kind, params = CASES[case]
    return kind, {**DEFAULTS[kind], **params}


def to_dict(case):
    kind, params = params_of(case)
    d = {"type": kind}
    for k, v in params.items():
        d[k] = {"type": "rgb", "value": v} if isinstance(v, list) else v
    return d


def closed_form_f(case, wi, wo):
    """f_r in float64 from the documented formula, shape (n, channels)."""
    kind, p = params_of(case)
    cos_i, cos_o = wi[:, 2], wo[:, 2]
    up = ((cos_i > 0) & (cos_o > 0))[:, None]
    if kind == "lambert":
        f = np.atleast_1d(np.array(p["reflectance"], float))[None, :] / math.pi
        return np.where(up, f, 0.0)
    kd = np.atleast_1d(np.array(p["diffuse_reflectance"], float))[None, :]
    ks = np.atleast_1d(np.array(p["specular_reflectance"], float))[None, :]
    e = p["exponent"]
    r = wi * np.array([-1.0, -1.0, 1.0])          # R = 2(N·V)N − V in the local frame
    cos_a = np.sum(r * wo, axis=1)[:, None]
    lobe = np.where(cos_a > 0, np.clip(cos_a, 0, 1) ** e, 0.0)
    return np.where(up, kd / math.pi + ks * (e + 2) / (2 * math.pi) * lobe, 0.0)


def random_dirs(n, seed, upper=False):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    if upper:
        v[:, 2] = np.abs(v[:, 2])
    return v


def spectrum_np(x, n):
    a = np.atleast_2d(np.array(x, dtype=np.float64))
    return np.broadcast_to(a, (a.shape[0], n)).T


@pytest.fixture(autouse=True)
def _rgb(variant_llvm_rgb):
    return variant_llvm_rgb


# ---------------------------------------------------------------------------- create / flags
def test_flags_and_components():
    lam = mi.load_dict({"type": "lambert"})
    assert lam.component_count() == 1
    assert mi.has_flag(lam.flags(), mi.BSDFFlags.DiffuseReflection)
    assert mi.has_flag(lam.flags(), mi.BSDFFlags.FrontSide)
    ph = mi.load_dict({"type": "phong"})
    assert ph.component_count() == 2
    # Component ids: 0 diffuse, 1 glossy (Mitsuba 0.6's phong.cpp swapped them).
    assert mi.has_flag(ph.flags(0), mi.BSDFFlags.DiffuseReflection)
    assert mi.has_flag(ph.flags(1), mi.BSDFFlags.GlossyReflection)
    assert not mi.has_flag(ph.flags(0), mi.BSDFFlags.GlossyReflection)


def test_component_selection_matches_sampled_component():
    ph = mi.load_dict({"type": "phong", "exponent": 10.0})
    n = 4096
    si = probe.interaction(np.tile([[0.3, 0.1, 0.948683]], (n, 1)))
    rng = np.random.default_rng(1)
    s1 = mi.Float(rng.random(n).astype(np.float32))
    s2 = mi.Point2f(*(mi.Float(rng.random(n).astype(np.float32)) for _ in range(2)))
    for comp, flag in ((0, mi.BSDFFlags.DiffuseReflection), (1, mi.BSDFFlags.GlossyReflection)):
        ctx = mi.BSDFContext()
        ctx.component = comp
        bs, w = ph.sample(ctx, si, s1, s2)
        valid = np.array(dr.any(w != 0))
        assert valid.sum() > n // 2
        comp_ids = np.broadcast_to(np.array(bs.sampled_component), (n,))
        types = np.broadcast_to(np.array(bs.sampled_type), (n,))
        assert np.all(comp_ids[valid] == comp)
        assert np.all(types[valid] == int(flag))
        # With one component enabled, eval contains only that lobe.
        value = np.array(ph.eval(ctx, si, bs.wo))[0]
        full = np.array(ph.eval(mi.BSDFContext(), si, bs.wo))[0]
        assert np.all(value <= full + 1e-6)


# ---------------------------------------------------------------------------- eval
@pytest.mark.parametrize("case", CASES)
def test_eval_matches_closed_form(case):
    """eval = f_r cos θ_o with f_r = ρ/π (lambert) or k_d/π + k_s (p+2)/(2π) cos^p α (phong)."""
    bsdf = mi.load_dict(to_dict(case))
    n = 20000
    wi = random_dirs(n, 1)
    wo = random_dirs(n, 2)
    # Put half the pairs near the mirror direction so that the narrow lobes are exercised.
    _, p = params_of(case)
    width = 1.0 / math.sqrt(max(p.get("exponent", 1.0), 1.0))
    near = (wi * np.array([-1, -1, 1]) + width * random_dirs(n, 3))
    near /= np.linalg.norm(near, axis=1, keepdims=True)
    wo[: n // 2] = near[: n // 2]
    value = np.array(bsdf.eval(mi.BSDFContext(), probe.interaction(wi), probe.to_vectors(wo))).T
    # Reference from the float32 inputs the plugin saw.
    wi32, wo32 = wi.astype(np.float32).astype(float), wo.astype(np.float32).astype(float)
    expected = closed_form_f(case, wi32, wo32) * np.maximum(wo32[:, 2:3], 0.0)
    expected = np.broadcast_to(expected, value.shape)
    # float32 round-off in cos α (a few ulp) is amplified p times by cos^p α.
    rtol = 1e-5 + 8 * p.get("exponent", 0.0) * 2.0 ** -24
    np.testing.assert_allclose(value, expected, rtol=rtol, atol=1e-6 * np.max(expected))


@pytest.mark.parametrize("case", CASES)
def test_eval_pdf_consistency(case):
    bsdf = mi.load_dict(to_dict(case))
    n = 4096
    si, wo = probe.interaction(random_dirs(n, 4, upper=True)), probe.to_vectors(random_dirs(n, 5))
    ctx = mi.BSDFContext()
    value, pdf = bsdf.eval_pdf(ctx, si, wo)
    assert np.array_equal(np.array(value), np.array(bsdf.eval(ctx, si, wo)))
    assert np.array_equal(np.array(pdf), np.array(bsdf.pdf(ctx, si, wo)))
    # pdf > 0 exactly where the BSDF is non-zero (both above the surface).
    nonzero = np.array(dr.any(value > 0))
    assert np.all(np.array(pdf)[nonzero] > 0)


@pytest.mark.parametrize("case", CASES)
def test_sample_weight_is_eval_over_pdf(case):
    bsdf = mi.load_dict(to_dict(case))
    n = 8192
    rng = np.random.default_rng(6)
    si = probe.interaction(random_dirs(n, 7, upper=True))
    s1 = mi.Float(rng.random(n).astype(np.float32))
    s2 = mi.Point2f(*(mi.Float(rng.random(n).astype(np.float32)) for _ in range(2)))
    ctx = mi.BSDFContext()
    bs, weight = bsdf.sample(ctx, si, s1, s2)
    value, pdf = bsdf.eval_pdf(ctx, si, bs.wo)
    weight, value, pdf = np.array(weight), np.array(value), np.array(pdf)
    valid = pdf > 0
    assert valid.mean() > 0.3, "almost no valid samples"
    np.testing.assert_allclose(np.array(bs.pdf)[valid], pdf[valid], rtol=1e-5)
    np.testing.assert_allclose(weight[:, valid], value[:, valid] / pdf[valid], rtol=1e-4, atol=1e-7)
    assert np.all(weight[:, ~valid] == 0)
    assert np.all(np.array(bs.eta) == 1.0)


@pytest.mark.parametrize("case", CASES)
def test_reciprocity(case):
    """f_r(ω_i, ω_o) = f_r(ω_o, ω_i): eval(wi, wo)/cos θ_o == eval(wo, wi)/cos θ_i."""
    bsdf = mi.load_dict(to_dict(case))
    n = 8192
    wi, wo = random_dirs(n, 8, upper=True), random_dirs(n, 9, upper=True)
    ctx = mi.BSDFContext()
    a = np.array(bsdf.eval(ctx, probe.interaction(wi), probe.to_vectors(wo)))
    b = np.array(bsdf.eval(ctx, probe.interaction(wo), probe.to_vectors(wi)))
    a, b = a / wo[:, 2].astype(np.float32), b / wi[:, 2].astype(np.float32)
    _, p = params_of(case)
    rtol = 1e-5 + 8 * p.get("exponent", 0.0) * 2.0 ** -24
    np.testing.assert_allclose(a, b, rtol=rtol, atol=1e-6)


# ---------------------------------------------------------------------------- stability
@pytest.mark.parametrize("case", ["lambert-gray", "phong-p0", "phong-default", "phong-p1e5"])
def test_finite_at_grazing_angles_and_extreme_exponents(case):
    bsdf = mi.load_dict(to_dict(case))
    cosines = np.array([1.0, 0.5, 1e-2, 1e-4, 1e-6, 0.0, -1e-6])
    n_each = 2048
    rng = np.random.default_rng(10)
    wi = np.zeros((len(cosines) * n_each, 3))
    c = np.repeat(cosines, n_each)
    phi = rng.random(len(c)) * 2 * math.pi
    s = np.sqrt(1 - c * c)
    wi[:, 0], wi[:, 1], wi[:, 2] = s * np.cos(phi), s * np.sin(phi), c
    n = len(wi)
    si = probe.interaction(wi)
    ctx = mi.BSDFContext()
    s1 = mi.Float(rng.random(n).astype(np.float32))
    # Include the extreme corners of the sample square (u = 0 and u -> 1).
    u = rng.random((n, 2)).astype(np.float32)
    u[:64] = 0.0
    u[64:128] = np.float32(1.0 - 2.0 ** -24)
    bs, weight = bsdf.sample(ctx, si, s1, mi.Point2f(mi.Float(u[:, 0]), mi.Float(u[:, 1])))
    value, pdf = bsdf.eval_pdf(ctx, si, bs.wo)
    for name, arr in (("weight", weight), ("eval", value), ("pdf", pdf), ("wo", bs.wo)):
        a = np.array(arr)
        assert np.all(np.isfinite(a)), f"{name} has NaN/Inf"
    assert np.all(np.array(weight) >= 0) and np.all(np.array(value) >= 0)
    wo = np.array(bs.wo)
    valid = np.array(pdf) > 0
    np.testing.assert_allclose(np.linalg.norm(wo[:, valid], axis=0), 1.0, atol=1e-5)


def test_phong_lobe_sampling_is_exact_at_huge_exponents():
    """cos α^(p+1) of lobe samples is U(0, 1) (inverse-CDF sampling), also at p = 1e5
    where 1 − cos α ~ 1e-5 and naive float32 arithmetic loses sin α."""
    # Imported here: the plugin module defines a class of the current variant's mi.BSDF, so it
    # can only be imported once the fixture has set a variant.
    from phonglab.plugins.phong import square_to_phong_lobe, square_to_phong_lobe_pdf

    n = 50000
    rng = np.random.default_rng(11)
    exponents = [0.0, 1.0, 100.0, 1e4, 1e5]
    level = sidak(ALPHA, len(exponents))
    for p in exponents:
        u = rng.random((n, 2)).astype(np.float32)
        v = square_to_phong_lobe(mi.Point2f(mi.Float(u[:, 0]), mi.Float(u[:, 1])), mi.Float(p))
        v = np.array(v).astype(np.float64)
        assert np.all(np.isfinite(v))
        np.testing.assert_allclose(np.linalg.norm(v, axis=0), 1.0, atol=1e-6)
        # 1 − cos α recovered from sin α (accurate) rather than from cos α (cancels).
        sin2 = v[0] ** 2 + v[1] ** 2
        one_minus_cos = np.where(v[2] < 0.5, 1.0 - v[2], sin2 / (1.0 + v[2]))
        t = np.exp((p + 1) * np.log1p(-one_minus_cos))
        assert stats.kstest(t, "uniform").pvalue > level, f"p = {p}"
        pdf = np.array(square_to_phong_lobe_pdf(mi.Vector3f(0, 0, 1), mi.Float(p)))
        np.testing.assert_allclose(pdf, (p + 1) / (2 * math.pi), rtol=1e-6)


# ---------------------------------------------------------------------------- chi^2
CHI2_CASES = [(e, deg) for e in (0.0, 1.0, 10.0, 100.0, 1000.0) for deg in (0.0, 45.0, 80.0)]


@pytest.mark.parametrize("exponent,theta_deg", CHI2_CASES,
                         ids=[f"p{e:g}-{d:g}deg" for e, d in CHI2_CASES])
def test_chi2_phong_sampling(exponent, theta_deg, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # mi.chi2 writes chi2_data.py on failure
    theta = math.radians(theta_deg)
    wi = [math.sin(theta), 0.0, math.cos(theta)]
    sample_func, pdf_func = mi.chi2.BSDFAdapter(
        "phong", {"type": "phong", "diffuse_reflectance": 0.3, "specular_reflectance": 0.6,
                  "exponent": exponent}, wi=wi)
    chi2 = mi.chi2.ChiSquareTest(domain=mi.chi2.SphericalDomain(), sample_func=sample_func,
                                 pdf_func=pdf_func, sample_dim=3, sample_count=400_000,
                                 res=101 if exponent < 1000 else 201,
                                 # Narrow lobes need a finer pdf integration per cell.
                                 ires=4 if exponent < 10 else 16,
                                 seed=int(exponent) + int(theta_deg))
    passed = chi2.run(significance_level=ALPHA, test_count=len(CHI2_CASES), quiet=True)
    # mi.chi2 passes vacuously when no sample lands: require a populated histogram.
    assert chi2.histogram is not None and float(dr.sum(chi2.histogram)[0]) > 0.5 * chi2.sample_count
    assert passed, chi2.messages


@pytest.mark.parametrize("theta_deg", [0.0, 60.0, 89.0])
def test_chi2_lambert_sampling(theta_deg, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    theta = math.radians(theta_deg)
    sample_func, pdf_func = mi.chi2.BSDFAdapter(
        "lambert", {"type": "lambert"}, wi=[math.sin(theta), 0.0, math.cos(theta)])
    chi2 = mi.chi2.ChiSquareTest(domain=mi.chi2.SphericalDomain(), sample_func=sample_func,
                                 pdf_func=pdf_func, sample_dim=3, sample_count=200_000)
    passed = chi2.run(significance_level=ALPHA, test_count=3, quiet=True)
    assert chi2.histogram is not None and float(dr.sum(chi2.histogram)[0]) > 0.9 * chi2.sample_count
    assert passed, chi2.messages


def test_chi2_catches_a_wrong_pdf(tmp_path, monkeypatch):
    """The harness itself: a pdf with (p+2) instead of (p+1) must be rejected."""
    monkeypatch.chdir(tmp_path)
    exponent = 20.0
    sample_func, pdf_func = mi.chi2.BSDFAdapter(
        "phong", {"type": "phong", "diffuse_reflectance": 0.0, "specular_reflectance": 1.0,
                  "exponent": exponent}, wi=[0, 0, 1])

    def wrong_pdf(wo, *args):
        return pdf_func(wo, *args) * (exponent + 2) / (exponent + 1)

    chi2 = mi.chi2.ChiSquareTest(domain=mi.chi2.SphericalDomain(), sample_func=sample_func,
                                 pdf_func=wrong_pdf, sample_dim=3, sample_count=200_000)
    assert not chi2.run(significance_level=ALPHA, quiet=True)


# ---------------------------------------------------------------------------- furnace / albedo
def directional_albedo(bsdf, theta, n, seed):
    """Monte Carlo directional albedo ∫ f_r cos θ_o dω_o = E[sample weight], and its SE."""
    a = radiometry.directional_albedo(bsdf, probe.direction(theta), n, seed)
    return a.mean, a.stderr


@pytest.mark.parametrize("theta_deg", [0.0, 30.0, 60.0, 85.0, 89.9])
def test_lambert_furnace_is_exactly_rho(theta_deg):
    """Lambert's sample weight is ρ for every sample: zero variance, albedo ρ at any incidence."""
    bsdf = mi.load_dict(to_dict("lambert-rgb"))
    mean, se = directional_albedo(bsdf, math.radians(theta_deg), 4096, 12)
    np.testing.assert_allclose(mean, [0.2, 0.5, 0.8], rtol=1e-6)
    assert np.all(se < 1e-6)


PHONG_ALBEDO = [(kd, ks, p) for kd, ks in ((0.0, 1.0), (0.3, 0.7), (0.5, 0.2))
                for p in (0.0, 1.0, 10.0, 100.0, 1e4)]


@pytest.mark.parametrize("kd,ks,exponent", PHONG_ALBEDO,
                         ids=[f"kd{a}-ks{b}-p{c:g}" for a, b, c in PHONG_ALBEDO])
def test_phong_albedo(kd, ks, exponent):
    """At normal incidence the albedo is exactly k_d + k_s (the (p+2)/(2π) normalization);
    at oblique incidence it is below, never significantly above, 1 when k_d + k_s <= 1."""
    bsdf = mi.load_dict({"type": "phong", "diffuse_reflectance": kd, "specular_reflectance": ks,
                         "exponent": exponent})
    z = stats.norm.ppf(1 - sidak(ALPHA, 2 * len(PHONG_ALBEDO)) / 2)
    mean, se = directional_albedo(bsdf, 0.0, 200_000, 13)
    assert abs(mean[0] - (kd + ks)) <= z * se[0] + 1e-5, (mean, se)
    for theta_deg in (45.0, 80.0, 89.0):
        mean, se = directional_albedo(bsdf, math.radians(theta_deg), 100_000, 14)
        assert mean[0] <= kd + ks + z * se[0] + 1e-5, (theta_deg, mean, se)


# ---------------------------------------------------------------------------- differentiability
def test_gradients_match_the_analytic_derivatives():
    """traverse exposes exponent and reflectances as differentiable: AD through eval equals
    d/dp [k_s (p+2)/(2π) c^p] = k_s c^p (1 + (p+2) ln c)/(2π) and d/dk_d = 1/π (times cos θ_o)."""
    bsdf = mi.load_dict({"type": "phong", "diffuse_reflectance": 0.4, "specular_reflectance": 0.5,
                         "exponent": 20.0})
    params = mi.traverse(bsdf)
    n = 512
    wi, wo = random_dirs(n, 21, upper=True), random_dirs(n, 22, upper=True)
    wo[: n // 2] = (wi * np.array([-1, -1, 1]))[: n // 2] + 0.1 * random_dirs(n // 2, 23)
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    wo[:, 2] = np.abs(wo[:, 2])
    wi32, wo32 = wi.astype(np.float32).astype(float), wo.astype(np.float32).astype(float)
    c = np.sum(wi32 * np.array([-1, -1, 1]) * wo32, axis=1)
    cos_o = wo32[:, 2]
    for key, expected in (
        ("exponent", np.where(c > 0, 0.5 * np.clip(c, 1e-30, 1) ** 20 * (1 + 22 * np.log(np.clip(c, 1e-30, 1)))
                              / (2 * math.pi), 0.0) * cos_o),
        ("diffuse_reflectance.value", cos_o / math.pi),
    ):
        dr.enable_grad(params[key])
        params.update()
        value = bsdf.eval(mi.BSDFContext(), probe.interaction(wi), probe.to_vectors(wo))
        dr.forward(params[key])
        grad = np.array(dr.grad(value))[0]
        dr.disable_grad(params[key])
        params.update()
        np.testing.assert_allclose(grad, expected, rtol=2e-4, atol=1e-6, err_msg=key)


def test_exponent_sweep_never_recompiles():
    """The exponent is an opaque kernel input: loading a phong and updating its exponent any
    number of times launches one and the same kernel (a baked float would recompile, ~0.4 s)."""
    bsdf = mi.load_dict({"type": "phong", "exponent": 30.0})
    params = mi.traverse(bsdf)
    si = probe.interaction(np.tile([[0.0, 0.0, 1.0]], (257, 1)))
    wo = probe.to_vectors(random_dirs(257, 30, upper=True))
    dr.eval(si, wo)
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        hashes, values = [], []
        for p in (None, 10.0, 20.0, 1e4):
            if p is not None:
                params["exponent"] = p
                params.update()
            dr.kernel_history()  # clear
            value = bsdf.eval(mi.BSDFContext(), si, wo)
            dr.eval(value)
            values.append(np.array(value)[0].copy())
            hashes.append(tuple(k["hash"] for k in dr.kernel_history()
                                if k["type"] == dr.KernelType.JIT))
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
    assert len(hashes[0]) >= 1 and len(set(hashes)) == 1, hashes
    assert not np.allclose(values[1], values[2])  # the new exponent did take effect
