"""Adaptive sampling (phonglab.engine.adaptive, ``phonglab render --adaptive``).

Statistical tests state their expectation and take their tolerance from the Monte Carlo
standard error (alpha = phonglab.stats.ALPHA, Sidak across a family); seeds are fixed.
Scenes are rendered at 16-32 pixels so the file stays in the fast tier.
"""

from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import ndimage, signal

from phonglab import cli, stats

from phonglab.engine import (adaptive, cost, exr, metrics, references, render, scenes, spp_map,
                             wavefront)
from phonglab.bench import adaptive_sweeps
from phonglab.bench import config as bench_config
from phonglab.errors import PhonglabError


def _load(name, variant="llvm_ad_rgb", **params):
    return scenes.load_scene(name, variant, **params)


@settings(max_examples=40, deadline=None)
@given(h=st.integers(1, 12), w=st.integers(1, 12), c=st.integers(1, 4), taps=st.integers(0, 3),
       seed=st.integers(0, 2 ** 16))
def test_separable_filter_is_scipy_convolve1d_twice(h, w, c, taps, seed):
    """The numpy filter the variance estimate uses equals scipy.ndimage's zero-padded
    convolution along both axes (any size, also images smaller than the kernel)."""
    rng = np.random.default_rng(seed)
    a, kernel = rng.random((h, w, c)), rng.random(2 * taps + 1)
    expected = ndimage.convolve1d(ndimage.convolve1d(a, kernel, axis=0, mode="constant"),
                                  kernel, axis=1, mode="constant")
    np.testing.assert_allclose(wavefront.separable_filter(kernel, a), expected, rtol=1e-12,
                               atol=1e-12)
    v = a[..., 0]
    box = ndimage.uniform_filter(v, 2 * taps + 1, mode="constant")
    ones = ndimage.uniform_filter(np.ones_like(v), 2 * taps + 1, mode="constant")
    np.testing.assert_allclose(wavefront.window_mean(v, taps), box / ones, rtol=1e-10)


def test_spp_map_png_colours_each_pixel_by_its_count(tmp_path):
    """The spp map preview: each film pixel a uniform square scaled up to >= 256 pixels a
    side, the least-sampled pixel at viridis' dark end, the most-sampled at its bright end."""
    from matplotlib import colormaps
    from PIL import Image

    spp = np.full((4, 8), 16)
    spp[1, 2], spp[3, 7] = 4, 1024
    path = spp_map.write_spp_map_png(tmp_path / "m.spp.png", spp)
    png = np.asarray(Image.open(path).convert("RGB"))
    scale = spp_map.SPP_PNG_MIN_SIDE // 4
    left = (png.shape[1] - 8 * scale) // 2
    lut = np.round(colormaps["viridis"]([0.0, 1.0])[:, :3] * 255)

    def square(y, x):   # the colours of film pixel (y, x) in the preview (title line: 14 px)
        block = png[14 + y * scale:14 + (y + 1) * scale, left + x * scale:left + (x + 1) * scale]
        return np.unique(block.reshape(-1, 3), axis=0)

    np.testing.assert_array_equal(square(1, 2), lut[:1])
    np.testing.assert_array_equal(square(3, 7), lut[1:])
    assert len(square(0, 0)) == 1 and not np.array_equal(square(0, 0), lut[:1])


def test_viridis_table_is_matplotlibs():
    """The spp map's stored colour table is matplotlib's viridis, rounded to 8 bits."""
    from matplotlib import colormaps

    from phonglab.engine.tonemap import VIRIDIS

    want = np.round(colormaps["viridis"](np.linspace(0.0, 1.0, 256))[:, :3] * 255)
    np.testing.assert_array_equal(VIRIDIS, want.astype(np.uint8))


def test_unbiased_image_mean_against_uniform_render(variant_llvm_rgb):
    """E[mean over pixels] is the same for adaptive and uniform sampling (the density-
    normalised filter and the data-dependent sample counts add no bias a test can see).

    Six adaptive renders (independent seeds) give a mean and its spread (t, 5 dof); the
    uniform render's 8 passes give its standard error; Sidak over the 3 channels.
    """
    scene = _load("gray_direct", res=24)
    means = np.array([adaptive.render_adaptive(scene, 0.03, seed=s).image.mean(axis=(0, 1))
                      for s in range(6)])
    uniform = render.render_scene(scene, 256, seed=100, passes=8)
    mu, se_u = uniform.mean_and_stderr()
    se_a = means.std(axis=0, ddof=1) / math.sqrt(len(means))
    t = np.abs(means.mean(axis=0) - mu) / np.sqrt(se_a ** 2 + se_u ** 2)
    assert np.all(t <= stats.t_critical(len(means) - 1, stats.ALPHA, 3)), (means.mean(0), mu, t)


def test_uniform_budget_reproduces_mi_render(variant_llvm_rgb):
    """With every pixel at the same count the wavefront is mi.render: the film's filter and
    weights, so the per-pixel difference of two independent renders is pure noise.

    Expected: mean over pixels of (x_a − x_u)² / (s_a² + s_u²) ≈ 1 (s from the estimators);
    the adaptive stderr is conservative (delta method, see adaptive docstring), so the ratio
    lies in (0.3, 1.5) — a filter or offset bug puts edge pixels off by many sigma.
    """
    scene = _load("cornell_phong", res=24)
    a = adaptive.render_adaptive(scene, 1e-4, seed=1, min_spp=64, max_spp=64)
    u = render.render_scene(scene, 64, seed=2, passes=8)
    ratio = np.mean((a.image - u.image) ** 2 / (a.stderr ** 2 + u.stderr ** 2 + 1e-12))
    assert 0.3 < ratio < 1.5, ratio
    assert np.all(a.spp == 64)


def test_spp_map_follows_the_highlight(variant_llvm_rgb):
    """gray_direct: black background (no variance), a glossy highlight and a silhouette:
    the spp map is far from uniform, and the background keeps the pilot's count."""
    r = adaptive.render_adaptive(_load("gray_direct", res=32), 0.01, seed=3)
    assert r.spp.min() == adaptive.MIN_SPP
    assert r.spp.max() >= 4 * r.spp.min()
    assert np.mean(r.spp == r.spp.min()) > 0.3       # the background
    assert np.std(r.spp) / np.mean(r.spp) > 0.5


def test_spp_map_uniform_on_a_uniform_scene(variant_llvm_rgb):
    """The furnace enclosure: every pixel sees L = Le/(1 − ρ) = 2 with the same variance, so
    the allocation N* ∝ √v is the same everywhere up to the estimates' noise."""
    r = adaptive.render_adaptive(_load("check_furnace_enclosure", res=16), 0.01, seed=4)
    assert r.spp.max() <= 2 * r.spp.min()
    assert np.std(r.spp) / np.mean(r.spp) < 0.25


def _relmse_spread(err2: np.ndarray, rfilter) -> float:
    """Standard deviation of mean_i d_i²/(r_i² + ε) for Gaussian errors of relative variance
    err2_i: Var = 2 Σ_ij ρ_ij² e_i² e_j² / P², ρ the correlation the filter gives
    neighbouring pixels of white noise (autocorrelation of the filter's pixel table A)."""
    a, _ = wavefront.filter_tables(rfilter)
    auto = signal.correlate2d(a, a)
    rho2 = (auto / auto.max()) ** 2
    e = err2.mean(axis=2) if err2.ndim == 3 else err2
    cross = signal.convolve2d(e, rho2, mode="same")
    return math.sqrt(2.0 * float(np.sum(e * cross)) * err2.shape[-1]) / err2.size


@pytest.mark.parametrize("name,target", [("gray_direct", 0.02), ("cornell_phong", 0.05)])
def test_achieved_error_meets_target(variant_llvm_rgb, name, target):
    """Against a converged reference (cached, 32², 4096 spp) the achieved relMSE is at most
    E² plus z·sd, sd the spread of a relMSE of independent-per-sample Gaussian errors with
    the estimated per-pixel variances (:func:`_relmse_spread`); Sidak over the 2 scenes."""
    params = {"res": 32}
    ref = references.reference(name, 4096, params=params)
    scene = _load(name, **params)
    r = adaptive.render_adaptive(scene, target, seed=5)
    achieved = metrics.rel_mse(r.image, ref.image, ref_stderr=ref.stderr)
    err2 = r.stderr.astype(np.float64) ** 2 / (ref.image.astype(np.float64) ** 2 + metrics.REL_EPS)
    sd = _relmse_spread(err2, scene.sensors()[0].film().rfilter())
    assert achieved <= target ** 2 + stats.z_critical(stats.ALPHA, 2) * sd, \
        (math.sqrt(achieved), target, r.estimated_error)


@pytest.mark.parametrize("integrator", ["path", "direct", "whitted"])
def test_integrators(variant_llvm_rgb, integrator):
    """path, direct and phonglab's Python whitted (radiance units, so the three agree in
    expectation at depth 2 with one point light): the adaptive image mean matches a uniform
    mi.render of the same integrator within their standard errors (Sidak: 3 x 3 channels)."""
    scene = _load("exponent_series", width=48, height=16, max_depth=2, integrator="path")
    integ = mi.load_dict({"type": integrator, "max_depth": 2} if integrator != "whitted" else
                         {"type": "whitted", "max_depth": 2, "units": "radiance"}) \
        if integrator != "direct" else mi.load_dict({"type": "direct"})
    means = np.array([adaptive.render_adaptive(scene, 0.02, seed=s, integrator=integ)
                      .image.mean(axis=(0, 1)) for s in range(4)])
    u = render.render_scene(scene, 64, seed=9, passes=8, integrator=integ)
    mu, se_u = u.mean_and_stderr()
    se_a = means.std(axis=0, ddof=1) / 2.0
    t = np.abs(means.mean(axis=0) - mu) / np.sqrt(se_a ** 2 + se_u ** 2 + 1e-300)
    assert np.all(t <= stats.t_critical(3, stats.ALPHA, 9)), (integrator, means.mean(0), mu)


def test_mono_and_spectral_variants():
    """Mono films have one channel, spectral renders are converted per sample to sRGB."""
    for variant, channels in (("llvm_ad_mono", 1), ("llvm_ad_spectral", 3)):
        r = adaptive.render_adaptive(_load("gray_direct", variant, res=16), 0.05, seed=1)
        assert r.image.shape == (16, 16, channels) and np.all(np.isfinite(r.image))


def test_scalar_variant_refused():
    with pytest.raises(PhonglabError, match="JIT variant"):
        adaptive.render_adaptive(_load("gray_direct", "scalar_rgb", res=4), 0.05)


def test_cli_writes_image_stderr_and_spp_map(tmp_path, capsys):
    out = tmp_path / "gd.exr"
    assert cli.main(["render", "gray_direct", "--adaptive", "--target-noise", "0.1",
                     "--max-spp", "64", "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "adaptively" in text and "spp map" in text
    image, meta = exr.read(out)
    spp, _ = exr.read(tmp_path / "gd.spp.exr")
    stderr, _ = exr.read(tmp_path / "gd.stderr.exr")
    assert spp.shape[:2] == image.shape[:2] == stderr.shape[:2]
    assert spp.min() >= adaptive.MIN_SPP and spp.max() <= 64
    assert meta["adaptive"] is True and meta["target_error"] == 0.1
    assert (tmp_path / "gd.png").is_file() and (tmp_path / "gd.spp.png").is_file()


def test_cli_stop_after_ends_the_passes(tmp_path, capsys):
    """--stop-after S is adaptive sampling's time limit: with a target the pilot cannot meet
    and a limit the pilot alone overruns, the render stops after the pilot and says why."""
    out = tmp_path / "gd.exr"
    assert cli.main(["render", "gray_direct", "--adaptive", "--target-noise", "1e-4",
                     "--stop-after", "1e-9", "-D", "res=16", "-o", str(out)]) == 0
    assert "stopped: --stop-after ran out" in capsys.readouterr().out
    _, meta = exr.read(out)
    assert meta["stopped"] == "max_seconds" and meta["passes"] == 1


@pytest.mark.parametrize("args,message", [
    (["--adaptive", "--target-noise", "0"], "target noise must be a relative RMSE"),
    (["--adaptive", "--target-noise", "-0.1"], "target noise must be a relative RMSE"),
    (["--adaptive", "--target-noise", "nan"], "target noise must be a relative RMSE"),
    (["--adaptive", "--target-noise", "inf"], "target noise must be a relative RMSE"),
    (["--adaptive"], "needs --target-noise"),
    (["--adaptive", "--by-time"], "needs --target-noise"),
    # --target-error is the planner's total error: not adaptive sampling's noise target
    (["--adaptive", "--target-error", "0.1"], "give --adaptive --target-noise N"),
    (["--adaptive", "--target-noise", "0.1", "--max-spp", "0"], "--max-spp"),
    (["--adaptive", "--target-noise", "0.1", "--stop-after", "-1"],
     "--stop-after must be a positive number of seconds"),
    (["--adaptive", "--target-noise", "0.1", "--stop-after", "nan"],
     "--stop-after must be a positive number of seconds"),
    # --max-seconds refuses plans: adaptive sampling's time limit is --stop-after
    (["--adaptive", "--target-noise", "0.1", "--max-seconds", "60"], "with --stop-after S"),
    (["--adaptive", "--target-noise", "0.1", "--spp", "8"], "drop --spp"),
    (["--max-spp", "8"], "add --adaptive --target-noise N"),
    (["--stop-after", "60"], "--stop-after applies to adaptive sampling"),
    (["--target-noise", "0.1"], "--target-noise applies to adaptive sampling; add --adaptive"),
    (["--target-error", "0.1", "--stop-after", "60"], "--stop-after applies to adaptive"),
    (["--max-seconds", "60"], "--max-seconds is about a plan's predicted time"),
    (["--by-time"], "--by-time is about adaptive sampling"),
])
def test_cli_bad_input_exits_2_before_work(tmp_path, capsys, args, message):
    out = tmp_path / "x.exr"
    assert cli.main(["render", "gray_direct", *args, "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err and err.count("\n") == 1
    assert not any(tmp_path.iterdir())


def test_cli_unwritable_spp_map_refused_before_render(tmp_path, capsys):
    (tmp_path / "x.spp.exr").mkdir()
    assert cli.main(["render", "gray_direct", "--adaptive", "--target-noise", "0.1",
                     "-o", str(tmp_path / "x.exr")]) == 2
    assert "spp map" in capsys.readouterr().err
    assert not (tmp_path / "x.exr").exists()


class _TinyConfig(bench_config.Config):
    """The bench part at test size (16², 2 seeds, one target; the oracle rows on the same two
    scenes at 16², not the bench's seven at 128² with 4096-spp references)."""

    adaptive_res = 16
    adaptive_oracle_scenes = {"gray_direct": (0.08, {"res": 16}),
                              "check_furnace_enclosure": (0.08, {"res": 16})}
    adaptive_scenes = ["gray_direct", "check_furnace_enclosure"]
    adaptive_spps = [4, 16]
    adaptive_targets = [0.08]
    adaptive_planned_targets = [0.08]
    adaptive_seeds = 2
    adaptive_reference_spp = 1024


def test_bench_part_writes_chart_speedups_and_report(tmp_path, monkeypatch, variant_llvm_rgb):
    """The 'adaptive' bench part at test size: rows of the three methods, equal-error speed-ups
    with their spread, the overhead verdict, the guard rows, both figures, and its section."""
    monkeypatch.setattr(adaptive_sweeps, "UNIFORM_SCENE_RES", 8)
    data = adaptive_sweeps.sweep_adaptive(tmp_path, _TinyConfig())
    gd = next(s for s in data["scenes"] if s["scene"] == "gray_direct")
    assert {r["method"] for r in gd["rows"]} == {"uniform", "adaptive", "planned"}
    for key in ("adaptive", "planned", "planned_render_only"):
        s = gd["speedups"][key]
        assert 0 < s["min"] <= s["median"] <= s["max"]
    assert data["overhead"]["cost_vs_uniform"] > 0 and "met" in data["overhead"]
    assert {g["neighbourhood"] for g in data["guards"]} == {True, False}
    assert (tmp_path / "adaptive_error_time.png").is_file()
    assert (tmp_path / "adaptive_sppmap.png").is_file()
    text = "\n".join(adaptive_sweeps.report_section(tmp_path, "docs/bench"))
    assert "Adaptive sampling" in text and "docs/bench/adaptive_error_time.png" in text
    assert "adaptive" in bench_config.PARTS
    for o in data["oracle"]:          # the cost-aware limit beside the sample one
        assert o["oracle_time"] >= 1 - 1e-9 and o["share_time"] > 0
    assert "oracle (time)" in text


def test_fit_time_sizes_a_pass_to_the_time_left():
    counts = np.array([0, 10, 30, 60])
    np.testing.assert_array_equal(adaptive.fit_time(counts, 1.0, 0.01), counts)   # 1 s needed
    np.testing.assert_array_equal(adaptive.fit_time(counts, 0.5, 0.01), [0, 5, 15, 30])
    assert not adaptive.fit_time(counts, 0.0, 0.01).any()
    assert not adaptive.fit_time(counts, -1.0, 0.01).any()


@pytest.mark.filterwarnings("error::RuntimeWarning")
def test_an_unreachable_target_stops_at_the_time_limit_without_overflow(variant_llvm_rgb):
    """E = 1e-6 asks for more samples than int64 holds: the counts are capped before the cast
    (no 'invalid value encountered in cast') and each pass is sized to the time left
    (fit_time), so at --max-seconds 2 the render ends within one pass of the limit (the
    assertion allows the pilot and twice the limit)."""
    r = adaptive.render_adaptive(_load("gray_direct", res=32), 1e-6, seed=1, max_seconds=2.0)
    assert r.stopped == "max_seconds"
    assert r.seconds <= 2 * 2.0 + r.passes[0]["seconds"], r.passes
    assert r.spp.max() <= adaptive.MAX_SPP
    assert all(0 < p["trace_seconds"] <= p["seconds"] for p in r.passes), r.passes


def test_oracle_speedup_is_the_neyman_gain_of_two_pixel_classes_and_one_for_uniform_variance():
    """Two equal halves of pixels with relative per-sample variances v₁, v₂: uniform sampling
    at n̄ samples has relMSE (v₁ + v₂)/(2n̄), the Neyman allocation n ∝ √v has
    ((√v₁ + √v₂)/2)²/n̄, so the oracle is 2(v₁ + v₂)/(√v₁ + √v₂)² (1 when v₁ = v₂)."""
    ref = np.full((4, 4, 3), 0.5)
    var = np.full((4, 4, 3), 0.01)
    assert adaptive.oracle_speedup(var, ref) == pytest.approx(1.0, abs=1e-12)
    var[:2] *= 16.0                                          # v₂ = 16 v₁
    assert adaptive.oracle_speedup(var, ref) == pytest.approx(2 * 17 / 25, rel=1e-12)
    # ε weights dark pixels by their absolute error: the same variance on a black reference
    # counts 1/(0.25 + ε) / (1/ε) as much.
    dark = ref.copy()
    dark[:2] = 0.0
    v1, v2 = 0.01 / (0.25 + metrics.REL_EPS), 0.01 / metrics.REL_EPS
    expect = 2 * (v1 + v2) / (math.sqrt(v1) + math.sqrt(v2)) ** 2
    assert adaptive.oracle_speedup(np.full((4, 4, 3), 0.01), dark) == pytest.approx(expect, rel=1e-12)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(1e-6, 1e3), min_size=2, max_size=30), st.integers(0, 2 ** 31 - 1))
def test_oracle_speedup_matches_the_relmse_of_the_neyman_allocation_and_is_at_least_one(vs, seed):
    """For any per-pixel variances, the oracle equals the ratio of the relMSE of uniform
    sampling to that of n_p ∝ √v_p at the same total samples (computed directly), and is >= 1."""
    v = np.asarray(vs)
    ref = np.zeros((1, len(v), 1))
    var = (v * metrics.REL_EPS)[None, :, None]               # v_p = var / (0 + ε)
    n = np.sqrt(v) / np.sqrt(v).sum() * len(v)               # Neyman, mean 1
    uniform, neyman = np.mean(v / 1.0), np.mean(v / n)
    got = adaptive.oracle_speedup(var, ref)
    assert got == pytest.approx(uniform / neyman, rel=1e-9)
    assert got >= 1.0 - 1e-12


def test_oracle_speedup_refuses_a_variance_map_that_is_not_finite():
    var = np.full((2, 2, 1), 0.1)
    var[0, 0, 0] = np.nan
    with pytest.raises(PhonglabError, match="finite variance map"):
        adaptive.oracle_speedup(var, np.ones((2, 2, 1)))


def test_exact_sums_split_the_image_error_over_source_pixels(variant_llvm_rgb):
    """Σ_p mean_c Var x_pc/(x_pc² + ε) from the exact squared-weight sums equals Σ_q u_q/N_q
    (the identity the allocation rests on), for any counts."""
    wf = wavefront.Wavefront(_load("gray_room", res=16))
    wf.squares = True
    wf.trace(np.random.default_rng(1).integers(4, 40, wf.pixels), 3)
    image = wf.image()
    var, u = wf.exact_variances(image, np.ones(wf.pixels, bool))
    n = wf.n.reshape(16, 16)
    lhs = np.mean(var / (image * image + metrics.REL_EPS))
    assert lhs == pytest.approx(np.mean(u / n), rel=1e-9)


def test_exact_estimate_matches_the_true_error_where_the_model_overestimates(variant_llvm_rgb):
    """gray_room (a light's edge against a dark ceiling), 32², 64 spp: the achieved relMSE
    against the cached reference is within z·sd of the exact estimate (sd of
    :func:`_relmse_spread`, Sidak over 2 seeds), while the position-free model's is more than
    twice it."""
    params = {"res": 32}
    ref = references.reference("gray_room", 4096, params=params)
    scene = _load("gray_room", **params)
    z = stats.z_critical(stats.ALPHA, 2)
    for seed in range(2):
        wf = wavefront.Wavefront(scene)
        wf.squares = True
        wf.trace(np.full(wf.pixels, 64), 10 + seed)
        image = wf.image()
        var, _ = wf.estimate(image)
        err2 = var / (ref.image ** 2 + metrics.REL_EPS)
        estimate = float(np.mean(err2))
        achieved = metrics.rel_mse(image, ref.image, ref_stderr=ref.stderr)
        sd = _relmse_spread(err2, scene.sensors()[0].film().rfilter())
        assert abs(achieved - estimate) <= z * sd, (achieved, estimate, sd)
        model = float(np.mean(wf.variance(image) / (ref.image ** 2 + metrics.REL_EPS)))
        assert model > 2 * achieved


def test_cost_map_counts_the_rays_of_paths_path_would_trace(variant_llvm_rgb):
    """Inside the closed furnace every ray hits a smooth wall: at max_depth 3 below rr_depth
    a path casts 3 intersections and 2 shadow rays (path.cpp: no emitter sample at the last
    vertex), exactly; other integrators have no cost map."""
    info = scenes.inspect_scene("check_furnace_enclosure", res=8)
    scene = _load("check_furnace_enclosure", res=8)
    wf = wavefront.Wavefront(scene, scenes.path_integrator(3, info))
    assert np.array_equal(wf.cost_map(seed=1), np.full((8, 8), cost.FIXED_COST + 5.0))
    assert wavefront.Wavefront(scene, mi.load_dict({"type": "direct"})).cost_map(1) is None


@settings(max_examples=30, deadline=None)
@given(st.lists(st.tuples(st.floats(1e-4, 1e2), st.floats(0.1, 10.0)), min_size=2, max_size=30))
def test_allocation_by_time_and_the_time_oracle(uc):
    """Without the guard, the allocation by time is √(u/c) sized to predict E² exactly, and
    the time oracle is the time uniform sampling needs for that error over the allocation's
    time (computed directly), and at least 1; with equal costs it is the sample oracle."""
    u, c = (np.asarray(x)[None, :] for x in zip(*uc))
    target = 0.05
    n = adaptive.allocation(u, target, neighbourhood=False, cost=c)
    assert np.mean(u / n) == pytest.approx(target ** 2, rel=1e-9)
    assert np.allclose(n / np.sqrt(u / c), (n / np.sqrt(u / c)).flat[0], rtol=1e-9)
    uniform_n = np.mean(u) / target ** 2                     # same error, one count for all
    gain = uniform_n * np.sum(c) / np.sum(c * n)
    assert adaptive.neyman_gain(u, c) == pytest.approx(gain, rel=1e-9)
    assert gain >= 1 - 1e-9
    assert adaptive.neyman_gain(u) == pytest.approx(adaptive.neyman_gain(u, np.ones_like(u)))


def test_by_time_render_keeps_its_cost_map_and_meets_its_estimate(variant_llvm_rgb):
    """A by-time render of a path-traced scene carries the pilot's cost map (every cost
    above the fixed part) and stops at the target like the count allocation."""
    scene = _load("gray_room", res=16)
    r = adaptive.render_adaptive(scene, 0.1, seed=3, by_time=True)
    assert r.cost is not None and r.cost.shape == (16, 16) and np.all(r.cost > cost.FIXED_COST)
    assert r.stopped == "target" and r.estimated_error <= 0.1 * (1 + adaptive.STOP_SLACK)
    assert adaptive.render_adaptive(scene, 0.1, seed=3).cost is None


def _exact_variances_numpy(wf, image, sources):
    """The delta method on the exact sums (wavefront module docstring), term by term in numpy
    from the whole tables T and Q copied to the host: the reference the device kernel of
    :meth:`Wavefront.exact_variances` is checked against."""
    h, w, c, k = wf.height, wf.width, wf.channels, len(wf.offsets)
    T = np.array(wf.splat, dtype=np.float64).reshape(wf.pixels, k, c + 1)
    Q = np.array(wf.splat2, dtype=np.float64).reshape(wf.pixels, k, 2 * c + 1)
    var, u = np.zeros((wf.pixels, c)), np.zeros(wf.pixels)
    x_all, weight = image.reshape(-1, c), wf.weight.reshape(-1)
    for q in np.flatnonzero(sources & (wf.n > 1)):
        n = float(wf.n[q])
        for j, (dy, dx) in enumerate(wf.offsets):
            py, px = q // w + dy, q % w + dx
            if not (0 <= py < h and 0 <= px < w) or weight[py * w + px] <= 0:
                continue
            p = py * w + px
            x = x_all[p]
            sz = T[q, j, :c] - x * T[q, j, c]
            sz2 = Q[q, j, 1 + c:] - 2 * x * Q[q, j, 1:1 + c] + x * x * Q[q, j, 0]
            term = np.maximum(sz2 - sz * sz / n, 0.0) / (n * (n - 1) * weight[p] ** 2)
            var[p] += term
            u[q] += n * np.mean(term / (x * x + metrics.REL_EPS))
    return var.reshape(h, w, c), u.reshape(h, w)


def test_exact_variances_on_the_device_are_the_delta_method_term_by_term(variant_llvm_rgb):
    """The device kernel of the exact sums gives what the formula gives evaluated term by term
    in float64 on the host, for every source pixel and for a subset (the pixels after the
    pilot), with pixels of 0 and 1 samples among them (no terms)."""
    wf = wavefront.Wavefront(_load("gray_room", res=12))
    wf.squares = True
    counts = np.random.default_rng(2).integers(0, 30, wf.pixels)
    counts[:5] = [0, 1, 1, 0, 2]
    wf.trace(counts, 4)
    image = wf.image()
    subset = np.random.default_rng(3).random(wf.pixels) < 0.3
    for sources in (np.ones(wf.pixels, bool), subset):
        var, u = wf.exact_variances(image, sources)
        ref_var, ref_u = _exact_variances_numpy(wf, image, sources)
        assert np.allclose(var, ref_var, rtol=1e-9, atol=0.0)
        assert np.allclose(u, ref_u, rtol=1e-9, atol=0.0)
        assert (u[~sources.reshape(u.shape)] == 0).all() and (u > 0).any()


def _model_numpy(wf, image, exclude=None):
    """The position-free model (wavefront module docstring) as convolutions with the separable
    kernels in numpy: (H, W, C) Var x_p and (H, W) u_q, the reference of the device kernels of
    :meth:`Wavefront.variance` and :meth:`Wavefront.source_variance`."""
    h, w, c = wf.height, wf.width, wf.channels
    f = wavefront.separable_filter
    n = wf.n.reshape(h, w, 1).astype(np.float64)
    s1, s2 = wf.s1.reshape(h, w, c), wf.s2.reshape(h, w, c)
    scale = np.where(n > 1, 1.0 / np.maximum(n * (n - 1.0), 1.0), 0.0)
    if exclude is not None:
        scale = scale * ~exclude.reshape(h, w, 1)
    x = image
    num = (f(wf.b, s2 * scale) - 2 * x * f(wf.b, s1 * scale) + x * x * f(wf.b, n * scale)
           - f(wf.a ** 2, s1 * s1 * scale / np.maximum(n, 1.0))
           + 2 * x * f(wf.a ** 2, s1 * scale) - x * x * f(wf.a ** 2, n * scale))
    den, lonely = f(wf.a, (n > 0).astype(float)), f(wf.a, (n == 1).astype(float)) > 0
    var = np.where((den > 0) & ~lonely, np.maximum(num, 0.0) / np.maximum(den * den, 1e-300),
                   np.inf)
    sigma2 = np.where(n > 1, (s2 - s1 * s1 / np.maximum(n, 1)) / np.maximum(n - 1, 1), 0.0)
    omega = np.where(den > 0, 1.0 / np.maximum(den * den, 1e-300), 0.0) / (x * x + metrics.REL_EPS)
    return var, np.mean(np.maximum(sigma2, 0.0) * f(wf.b, omega), axis=2)


@pytest.mark.parametrize("rfilter", ["gaussian", "box"])
def test_the_position_free_model_on_the_device_is_its_convolutions(variant_llvm_rgb, rfilter):
    """The device kernels of the position-free model give what its convolutions give in numpy
    (gray_room's gaussian filter: 5x5 offsets; nb_sphere_row's box: one), with sources of 0 and 1 samples (unknown
    targets: inf) and an excluded set."""
    scene = _load("gray_room", res=12) if rfilter == "gaussian" else \
        _load("nb_sphere_row", width=16, height=8)           # its film's filter is a box
    wf = wavefront.Wavefront(scene)
    assert len(wf.offsets) == (25 if rfilter == "gaussian" else 1)
    counts = np.random.default_rng(5).integers(0, 30, wf.pixels)
    counts[:6] = [0, 1, 1, 0, 2, 0]
    wf.trace(counts, 6)
    image = wf.image()
    exclude = np.random.default_rng(6).random(wf.pixels) < 0.3
    for ex in (None, exclude):
        var, ref_var = wf.variance(image, ex), _model_numpy(wf, image, ex)[0]
        assert np.array_equal(np.isinf(var), np.isinf(ref_var)) and np.isinf(var).any()
        fin = np.isfinite(ref_var)
        np.testing.assert_allclose(var[fin], ref_var[fin], rtol=1e-9, atol=1e-300)
    u, ref_u = wf.source_variance(image), _model_numpy(wf, image)[1]
    np.testing.assert_allclose(u, ref_u, rtol=1e-9, atol=0.0)
    assert (u > 0).any()


def test_jit_array_gives_one_kernel_wherever_numpy_put_the_buffer(variant_llvm_rgb):
    """Dr.Jit 1.5 compiles another kernel for a 64-byte aligned host array than for one that
    is not: the same computation on views at every 4-byte offset of one buffer gives two
    kernel hashes through ``mi.UInt32`` and one through :func:`wavefront.jit_array`, with
    the same values."""
    buf = np.arange(4096 + 64, dtype=np.uint32)

    def hashes(convert):
        seen, values = set(), set()
        for off in range(0, 64, 4):
            view = buf[off // 4:off // 4 + 4096]
            dr.set_flag(dr.JitFlag.KernelHistory, True)
            out = convert(view) * 3 + 1
            dr.eval(out)
            history = dr.kernel_history()
            dr.set_flag(dr.JitFlag.KernelHistory, False)
            seen |= {str(k["hash"]) for k in history if str(k["type"]) == "KernelType.JIT"}
            assert np.array_equal(np.array(out), view * 3 + 1)
            values.add(view.ctypes.data % 64 == 0)
        return seen, values

    raw, aligned_seen = hashes(mi.UInt32)
    assert aligned_seen == {True, False} and len(raw) == 2
    ours, _ = hashes(lambda a: wavefront.jit_array(mi.UInt32, a))
    assert len(ours) == 1
