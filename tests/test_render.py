"""Rendering: the CLI's EXR/PNG output with provenance, and lambert == diffuse in a full scene."""

from __future__ import annotations

import numpy as np
from scipy import stats

from phonglab.stats import ALPHA, sidak
from phonglab import cli
from phonglab.engine import exr
from phonglab.engine.render import render_scene
from phonglab.engine.scenes import load_scene


def test_render_cli_writes_exr_png_and_provenance(tmp_path, capsys, variant_llvm_rgb):
    out = tmp_path / "c.exr"
    assert cli.main(["render", "cornell_phong", "--spp", "4", "--seed", "3", "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert str(out) in printed and "PNG" in printed
    image, meta = exr.read(out)
    assert image.shape == (256, 256, 3) and image.dtype == np.float32
    assert np.all(np.isfinite(image)) and image.mean() > 0.05
    for key in ("scene", "scene_sha256", "variant", "spp", "seed", "integrator", "max_depth",
                "render_seconds", "phonglab_version", "mitsuba_version"):
        assert key in meta, key
    assert meta["spp"] == 4 and meta["seed"] == 3 and meta["max_depth"] == 8
    assert meta["variant"] == "llvm_ad_rgb"
    assert out.with_suffix(".png").stat().st_size > 1000


def test_render_cli_sets_scene_parameters(tmp_path, capsys, variant_llvm_rgb):
    """-D NAME=VALUE reaches the scene (film size) in every render mode, and is recorded;
    a malformed one or a name the scene does not use exits 2 with one sentence."""
    for mode in (["--spp", "4"], ["--target-error", "0.05"],
                 ["--adaptive", "--target-noise", "0.2"]):
        out = tmp_path / f"{mode[0].strip('-')}.exr"
        assert cli.main(["render", "gray_direct", "-D", "res=24", *mode, "-o", str(out)]) == 0
        image, meta = exr.read(out)
        assert image.shape[:2] == (24, 24), mode
        assert meta["params"]["res"] == "24", mode
    capsys.readouterr()
    assert cli.main(["render", "gray_direct", "-D", "colour=red", "--spp", "1",
                     "-o", str(tmp_path / "x.exr")]) == 2
    assert "does not use the parameter" in capsys.readouterr().err


def test_render_passes_give_an_honest_standard_error(variant_llvm_rgb, scenes_dir):
    """Per-pixel SE from passes predicts the spread of independent renders: the difference of
    two independent renders, divided by its SE, has unit variance (pixels are correlated by
    the reconstruction filter, so their mean is tested with the pass-level SE instead)."""
    scene = load_scene(scenes_dir / "cornell_phong.xml", res=24, spp=64)
    a = render_scene(scene, spp=64, seed=1, passes=16)
    b = render_scene(scene, spp=64, seed=2, passes=16)
    se = np.sqrt(a.stderr ** 2 + b.stderr ** 2)
    ok = se > 0
    z = (a.image - b.image)[ok] / se[ok]
    # Each z is a Welch t with ~30 d.o.f.: E[z^2] ~ 30/28; pixels are not independent, so the
    # bound is loose but fails for an SE off by more than ~20 %.
    assert 0.8 < z.var() < 1.5, z.var()
    (ma, sa), (mb, sb) = a.mean_and_stderr(), b.mean_and_stderr()
    zmean = (ma - mb) / np.sqrt(sa ** 2 + sb ** 2)
    assert np.all(np.abs(zmean) < stats.t.ppf(1 - sidak(ALPHA, 3) / 2, df=2 * (16 - 1))), zmean


def test_lambert_and_diffuse_render_statistically_equal(variant_llvm_rgb, scenes_dir):
    """Same scene, walls `lambert` vs built-in `diffuse`, independent seeds: no pixel differs
    at the Šidák-corrected level, and the mean difference is within its standard error."""
    spp, passes = 64, 16
    imgs = {}
    for k, wall in enumerate(("lambert", "diffuse")):
        scene = load_scene(scenes_dir / "cornell_phong.xml", res=24, spp=spp, wall=wall)
        imgs[wall] = render_scene(scene, spp=spp, seed=10 + k, passes=passes)
    a, b = imgs["lambert"], imgs["diffuse"]
    diff = a.image - b.image
    se = np.sqrt(a.stderr ** 2 + b.stderr ** 2)
    ok = se > 0
    # Welch t on pass means, d.o.f. ~ 2 (passes - 1); Šidák over every pixel and channel.
    t = diff[ok] / se[ok]
    p = 2 * stats.t.sf(np.abs(t), df=2 * (passes - 1))
    assert p.min() > sidak(ALPHA, t.size), f"min p {p.min():.3g}"
    (ma, sa), (mb, sb) = a.mean_and_stderr(), b.mean_and_stderr()
    zmean = (ma - mb) / np.sqrt(sa ** 2 + sb ** 2)
    assert np.all(np.abs(zmean) < stats.t.ppf(1 - sidak(ALPHA, 3) / 2, df=2 * (16 - 1))), zmean


def test_the_same_test_detects_a_10_percent_darker_lambert(variant_llvm_rgb, scenes_dir, tmp_path):
    """The comparison is not vacuous: lambert walls 10 % darker (a 5-6 % darker image at this noise level of ~1.5 %) are detected in the mean."""
    import mitsuba as mi

    spp, passes = 64, 16
    scene_a = load_scene(scenes_dir / "cornell_phong.xml", res=24, spp=spp, wall="lambert")
    params = mi.traverse(scene_a)
    for key in list(params.keys()):
        if key.endswith("reflectance.value") and "glossy" not in key and "box" not in key:
            params[key] = params[key] * 0.9
    params.update()
    scene_b = load_scene(scenes_dir / "cornell_phong.xml", res=24, spp=spp, wall="diffuse")
    a = render_scene(scene_a, spp=spp, seed=20, passes=passes)
    b = render_scene(scene_b, spp=spp, seed=21, passes=passes)
    (ma, sa), (mb, sb) = a.mean_and_stderr(), b.mean_and_stderr()
    zmean = (ma - mb) / np.sqrt(sa ** 2 + sb ** 2)
    assert np.any(np.abs(zmean) > stats.t.ppf(1 - sidak(ALPHA, 3) / 2, df=2 * (passes - 1))), zmean


def test_preview_exposure_only_darkens_images_beyond_one():
    from phonglab.engine.tonemap import auto_exposure

    rng = np.random.default_rng(0)
    radiance = rng.random((32, 32, 3)) * 0.9           # a radiance render: previewed as is
    assert auto_exposure(radiance, darken_only=True) == 0.0
    graphics = radiance * 50.0                          # graphics units: 99th pct ~ 44.6
    ev = auto_exposure(graphics, darken_only=True)
    assert ev < 0
    np.testing.assert_allclose(np.percentile(graphics, 99) * 2.0 ** ev, 0.8, rtol=1e-9)
    assert auto_exposure(np.zeros((4, 4, 3))) == 0.0


def test_render_file_with_another_sampler_records_it(tmp_path, variant_llvm_rgb):
    from phonglab.engine import exr, render

    out = tmp_path / "gd.exr"
    r = render.render_file("gray_direct", out, spp=40, sampler="multijitter", progress=False)
    assert r.pass_spp == [6] * 8 and r.metadata["spp"] == 48
    assert r.metadata["sampler"] == "MultijitterSampler"
    assert exr.read(out)[1]["sampler"] == "MultijitterSampler"
    plain = render.render_file("gray_direct", tmp_path / "p.exr", spp=40, progress=False)
    assert plain.metadata["sampler"] == "IndependentSampler" and plain.metadata["spp"] == 40
