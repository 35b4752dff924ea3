"""Tests of the planner (phonglab.planner, ``phonglab plan``, ``phonglab render --target-error``).

Cheapest first: scene inspection (XML only) -> variant/backend choice -> plans from small pilots
(res 32) -> achieved error against a converged reference -> the CLI.

The error is phonglab's relative RMSE, E = sqrt(mean((x - r)^2/(r^2 + 0.01))) over every pixel
and channel, r the converged full-depth image (phonglab.engine.metrics.relative_rmse with the
reference's noise subtracted; phonglab.engine.references.reference).
"""

from __future__ import annotations

import json
import math

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from phonglab import planner, runtime, stats

from phonglab.engine import exr, metrics, references, render, scenes
from phonglab.cli import main
from phonglab.errors import PhonglabError
from phonglab.planner import PlanOptions, benchmark, choice

RES = {"res": 32}


@pytest.fixture(autouse=True, scope="module")
def full_pilot():
    """These tests check every step of the pilot on tiny films, where each render is
    cheaper than the pilot and the plan would otherwise go straight to full depth
    (planning.STRAIGHT; tested on its own by asking for it).  Module scope: the module's
    shared plans are made with it too."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(planner.planning, "STRAIGHT", False)
        yield
TARGET = 0.05
ALLOWED = planner.BIAS_FRACTION * TARGET


def _write(tmp_path, body: str, defaults: str = "") -> str:
    path = tmp_path / "scene.xml"
    path.write_text(f'<scene version="3.0.0">{defaults}{body}</scene>')
    return str(path)


# --- scene inspection: no rendering -------------------------------------------------------------

def test_gray_direct_is_mono_without_delta_bsdfs():
    info = scenes.inspect_scene("gray_direct")
    assert info.colored == [] and info.spectral == [] and info.delta_bsdfs == []
    assert info.gray_values == 4          # k_d, k_s, the light's black BSDF, its radiance
    assert info.color == "mono"


def test_cornell_is_rgb_and_names_the_coloured_walls():
    info = scenes.inspect_scene("cornell_phong")
    assert info.color == "rgb"
    assert any("'red'" in c for c in info.colored) and any("'green'" in c for c in info.colored)


def test_glass_slab_is_rgb_with_a_dielectric():
    info = scenes.inspect_scene("glass_slab")
    assert info.color == "rgb" and info.delta_bsdfs == ["dielectric"]
    assert any("checkerboard" in c for c in info.colored)


@pytest.mark.parametrize("body, color", [
    ('<bsdf type="diffuse"><spectrum name="reflectance" value="0.5"/></bsdf>', "mono"),
    ('<bsdf type="diffuse"><spectrum name="reflectance" value="400:0.1, 700:0.9"/></bsdf>',
     "spectral"),
    ('<emitter type="constant"><spectrum name="radiance" type="blackbody">'
     '<float name="temperature" value="3000"/></spectrum></emitter>', "spectral"),
    ('<bsdf type="conductor"><string name="material" value="Au"/></bsdf>', "spectral"),
    ('<bsdf type="conductor"/>', "mono"),
    ('<bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.2, 0.2"/></bsdf>'
     '<emitter type="constant"><rgb name="radiance" value="1, 0.9, 0.8"/></emitter>', "rgb"),
], ids=["uniform-spectrum", "wavelength-list", "blackbody", "measured-conductor",
        "perfect-mirror", "coloured-emitter"])
def test_colour_model_follows_the_data(tmp_path, body, color):
    assert scenes.inspect_scene(_write(tmp_path, body)).color == color


def test_defaults_and_overrides_are_substituted(tmp_path):
    path = _write(tmp_path, '<bsdf type="diffuse"><rgb name="reflectance" value="$c"/></bsdf>',
                  '<default name="c" value="0.2, 0.5, 0.1"/>')
    assert scenes.inspect_scene(path).color == "rgb"
    assert scenes.inspect_scene(path, c="0.3, 0.3, 0.3").color == "mono"


def test_unresolved_substitution_is_a_user_error(tmp_path):
    path = _write(tmp_path, '<bsdf type="diffuse"><rgb name="reflectance" value="$c"/></bsdf>')
    with pytest.raises(PhonglabError, match=r"'\$c' is used but has no <default>"):
        scenes.inspect_scene(path)


# --- variant and backend --------------------------------------------------------------------------

def test_variant_steps_up_only_when_needed():
    assert runtime.variant_for("mono", "llvm") == ("llvm_ad_mono", [])
    assert runtime.variant_for("mono", "llvm", polarized=True)[0] == "llvm_ad_mono_polarized"
    # Mitsuba builds no rgb_polarized and no scalar_mono: the next richer model, with a note.
    variant, notes = runtime.variant_for("rgb", "llvm", polarized=True)
    assert variant == "llvm_ad_spectral_polarized" and notes
    variant, notes = runtime.variant_for("mono", "scalar")
    assert variant == "scalar_rgb" and notes


def test_backend_is_the_best_that_works_here():
    backend, why = runtime.available_backend()
    if not dr.has_backend(dr.JitBackend.CUDA):
        assert backend != "cuda" and "CUDA" in why
    if runtime.configure().usable:
        assert backend in ("cuda", "llvm")


@pytest.mark.parametrize("target", [0, -0.01, float("nan"), 10])
def test_bad_target_is_a_user_error(target):
    with pytest.raises(PhonglabError, match="target error must be a relative RMSE"):
        PlanOptions(target)


def test_non_path_integrator_is_refused(tmp_path):
    path = _write(tmp_path, '<integrator type="direct"/><shape type="sphere"/>')
    with pytest.raises(PhonglabError, match="plans path-traced scenes"):
        planner.plan(path, PlanOptions(0.05))


def test_polarized_only_when_asked_and_then_it_plans():
    """phonglab's plugins are ideal depolarizers (like diffuse), so a polarized plan works."""
    plan = planner.plan("gray_direct", PlanOptions(TARGET, polarized=True, params=RES))
    assert plan.variant.endswith("_polarized")


def test_spectral_data_is_planned_spectral(tmp_path):
    path = _write(tmp_path, """
        <integrator type="path"/>
        <sensor type="perspective">
            <transform name="to_world"><lookat origin="0,0,4" target="0,0,0" up="0,1,0"/></transform>
            <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film>
        </sensor>
        <shape type="sphere"><bsdf type="lambert">
            <spectrum name="reflectance" value="400:0.2, 550:0.5, 700:0.8"/>
        </bsdf></shape>
        <emitter type="constant"><spectrum name="radiance" value="1"/></emitter>""")
    p = planner.plan(path, PlanOptions(0.1))
    assert p.color == "spectral" and p.variant.endswith("_spectral")
    # Constant environment + convex sphere: everything arrives within 2 segments.
    assert p.max_depth == 2


# --- plans from small pilots -----------------------------------------------------------------------

@pytest.fixture(scope="module")
def plans():
    return {name: planner.plan(name, PlanOptions(TARGET, params=RES))
            for name in ("gray_direct", "cornell_phong", "glass_slab")}


def _bias(plan, depth):
    return next(s.bias for s in plan.pilot.depths if s.depth == depth)


def test_gray_direct_is_planned_mono_with_depth_2(plans):
    p = plans["gray_direct"]
    assert p.variant.endswith("_mono") and p.color == "mono"
    assert p.max_depth == 2
    # Header of gray_direct.xml: depth 1 renders nothing (all energy omitted), depth >= 3 adds
    # exactly zero, so the depth-2 bias is zero up to float rounding of the sums.
    assert _bias(p, 1) > ALLOWED and _bias(p, 2) < 1e-6


def test_cornell_is_planned_rgb_deeper(plans):
    p = plans["cornell_phong"]
    assert p.variant == "llvm_ad_rgb" or p.variant.endswith("_rgb")
    assert p.max_depth > 2
    assert _bias(p, 2) > ALLOWED


def test_glass_keeps_the_depth_of_its_delta_chain(plans):
    p = plans["glass_slab"]
    # Header of glass_slab.xml: the wall seen through the slab needs max_depth >= 4.
    assert p.max_depth >= 4 and p.variant.endswith("_rgb")
    assert _bias(p, 3) > ALLOWED
    assert any("dielectric" in r for r in p.reasons)


@pytest.mark.parametrize("name", ["gray_direct", "cornell_phong", "glass_slab"])
def test_plan_is_the_smallest_depth_and_spp_meeting_the_target(plans, name):
    p = plans[name]
    assert _bias(p, p.max_depth) <= ALLOWED
    shallower = [s for s in p.pilot.depths if 1 <= s.depth < p.max_depth]
    failing = max(s.depth for s in shallower)
    assert _bias(p, failing) > ALLOWED
    if any("were not searched" in r for r in p.reasons):
        # a ladder depth, the gap below it priced as not worth its render (gap_value < 1)
        assert p.max_depth in planner.pilot.DEPTH_LADDER and failing < p.max_depth - 1
        assert "could save the render at most" in next(r for r in p.reasons
                                                       if r.startswith("max_depth"))
    else:
        assert failing == p.max_depth - 1
    noise1 = next(s.noise_per_sample for s in p.pilot.depths if s.depth == p.max_depth)
    u = p.uniform
    assert math.isclose(u.predicted_noise, noise1 / math.sqrt(u.spp), rel_tol=1e-9)
    assert math.isclose(u.predicted_error, math.hypot(u.predicted_bias, u.predicted_noise),
                        rel_tol=1e-9)
    assert u.predicted_error <= TARGET
    if u.spp > 1:  # one sample fewer would miss the target
        assert math.hypot(u.predicted_bias, noise1 / math.sqrt(u.spp - 1)) > TARGET
    assert u.predicted_seconds > 0 and u.seconds_per_sample > 0


def test_plan_json_has_the_documented_fields(plans):
    d = json.loads(plans["cornell_phong"].to_json())
    for key in ("variant", "max_depth", "spp", "predicted_error", "predicted_seconds", "reasons"):
        assert key in d
    assert d["variant"] == plans["cornell_phong"].variant and isinstance(d["reasons"], list)


def test_plan_holds_its_pilot_scene_outside_its_json(plans):
    p = plans["cornell_phong"]
    assert p.loaded is not None and p.info is not None and p.info.path.name == "cornell_phong.xml"
    d = p.to_dict()
    assert "loaded" not in d and "info" not in d
    assert json.loads(p.to_json()) == json.loads(json.dumps(d))


def test_noise_target_is_what_the_total_error_leaves_to_noise():
    """metrics.noise_target: E² = b² + n², so n = √(E² − b²); b = 0 gives E; floored at E/100."""
    assert metrics.noise_target(0.05, 0.03) == pytest.approx(0.04)
    assert metrics.noise_target(0.05) == 0.05
    assert metrics.noise_target(0.05, 0.06) == pytest.approx(0.0005)
    uniform = planner.planning.Uniform(16, 8, 0.05, 0.03, 0.04, 1.0, 1e-9, 1e-3)
    p = planner.Plan("s.xml", PlanOptions(0.05), "llvm_ad_rgb", "llvm", "rgb", 8, (8, 8),
                     uniform, choice.Option("path", "adaptive", 12.0, 0.8, 0.16),
                     planner.planning.PilotRecord(64, 1.0, 1))
    assert p.noise_target == pytest.approx(0.04)


def test_render_plan_reuses_the_pilot_scene_and_reports_its_error(plans, tmp_path, monkeypatch):
    """planner.render_plan renders with the scene the pilot loaded (no second load), without
    files or into the CLI's file set, and reports achieved (given a reference) and estimated
    error; the same seed gives the same image on both routes."""
    p = plans["gray_direct"]
    ref = references.reference("gray_direct", 1024, params=RES)

    def no_load(*args, **kwargs):
        raise AssertionError("the planned render loaded the scene again")

    monkeypatch.setattr(render, "load_scene", no_load)
    done = planner.render_plan(p, seed=4, reference=ref)
    w, h = p.resolution
    assert done.image.shape[:2] == (h, w)
    err = done.error
    assert err.achieved == metrics.relative_rmse(done.image, ref.image, ref_stderr=ref.stderr)
    assert err.reference_spp == ref.spp and err.target == TARGET
    assert err.bias == p.uniform.predicted_bias
    assert err.estimated == pytest.approx(math.hypot(err.noise, p.uniform.predicted_bias))
    said = done.describe()   # what `render --target-error` prints of it
    assert f"achieved {err.achieved:.4g}" in said and f"target {TARGET:g}" in said
    out = tmp_path / "gd.exr"
    filed = planner.render_plan(p, seed=4, out=out, reference=ref)
    image, meta = exr.read(out)
    assert meta["target_error"] == TARGET and meta["planned"]["model"] == p.render.model
    np.testing.assert_allclose(image.reshape(done.image.shape), done.image, rtol=1e-5,
                               atol=1e-6)
    assert filed.error.achieved == pytest.approx(err.achieved, rel=1e-4)


def test_explicit_settings_override_the_plan():
    p = planner.plan("gray_direct", PlanOptions(TARGET, variant="llvm_ad_rgb", max_depth=1,
                                                spp=4, params=RES))
    assert (p.variant, p.max_depth, p.uniform.spp) == ("llvm_ad_rgb", 1, 4)
    # Depth 1 sees no emitter: the whole image is bias, far above the target, and it says so.
    assert p.uniform.predicted_error > TARGET and any("misses the target" in r for r in p.reasons)


# --- achieved error ---------------------------------------------------------------------------------

@pytest.mark.parametrize("name", ["gray_direct", "cornell_phong", "glass_slab"])
def test_achieved_error_is_near_the_target(plans, name):
    """The planned render's relative RMSE lies in [0.5, 1.5] x the target.

    The reference has 16x the planned spp (its noise, about E/4, is subtracted by
    metrics.relative_rmse); the achieved error of one render over 32 x 32 x C values scatters by a few
    percent, so the window tests the planner's prediction, not the luck of one seed.
    """
    p = plans[name]
    ref = references.reference(name, max(1024, 16 * p.uniform.spp), params=RES)
    scene = scenes.load_scene(name, p.variant, **RES)
    info = scenes.inspect_scene(name, **RES)
    result = render.render_scene(scene, p.uniform.spp, seed=0, passes=p.uniform.passes,
                                 integrator=scenes.path_integrator(p.max_depth, info))
    achieved = metrics.relative_rmse(result.image, ref.image, ref_stderr=ref.stderr)
    assert 0.5 * TARGET <= achieved <= 1.5 * TARGET, (name, achieved, p.summary())


def test_achieved_error_subtracts_the_reference_noise():
    rng = np.random.default_rng(1)
    truth = np.full((64, 64, 3), 0.5)
    se = 0.01
    image = truth + rng.normal(0, 0.02, truth.shape)
    reference = truth + rng.normal(0, se, truth.shape)
    # Expected: the image's own relative noise 0.02/√(0.5² + ε) = 0.0392, not
    # √(0.02² + 0.01²)/√(0.5² + ε).
    got = metrics.relative_rmse(image, reference, ref_stderr=np.full_like(truth, se))
    assert abs(got - 0.02 / math.sqrt(0.5 ** 2 + metrics.REL_EPS)) < 0.002
    # A gray scene's mono render against an RGB reference: the reference's channels (and their
    # noise) are equal, so its luminance is the same gray value with the same standard error.
    gray_ref = np.repeat(reference[..., :1], 3, axis=2)
    mono = image[..., :1]
    got = metrics.relative_rmse(mono, gray_ref, ref_stderr=np.full_like(truth, se))
    assert metrics.luminance(gray_ref, keepdims=True).shape == (64, 64, 1)
    assert abs(got - 0.02 / math.sqrt(0.5 ** 2 + metrics.REL_EPS)) < 0.004


# --- CLI -----------------------------------------------------------------------------------------

def test_cli_plan_json(capsys):
    assert main(["plan", "gray_direct", "--target-error", "0.1", "--set", "res=32", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["variant"].endswith("_mono") and d["max_depth"] == 2 and d["spp"] >= 1


def test_cli_plan_prints_reasons(capsys):
    assert main(["plan", "cornell_phong", "--target-error", "0.2", "--set", "res=16"]) == 0
    out = capsys.readouterr().out
    assert "variant   llvm_ad_rgb" in out and "because:" in out and "max_depth" in out


def test_cli_bad_target_exits_2(capsys):
    assert main(["plan", "gray_direct", "--target-error", "-1"]) == 2
    assert "target error must be" in capsys.readouterr().err


def test_cli_render_with_target_error(tmp_path, capsys):
    """The plan is made for the render's --seed (its pilot takes the seeds after it), and
    the render runs with that seed."""
    out = tmp_path / "gd.exr"
    assert main(["render", "gray_direct", "--target-error", "0.1", "--seed", "3",
                 "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "predicted" in text and "error:" in text and "max_depth 2" in text
    image, meta = exr.read(out)
    assert meta["target_error"] == 0.1 and meta["max_depth"] == 2
    assert meta["seed"] == 3 and meta["planned"]["pilot_seed"] == 3 + planner.PILOT_SEED
    assert image.ndim == 2                  # mono: one channel


def test_cli_render_explicit_settings_override_the_plan(tmp_path, capsys):
    out = tmp_path / "gd.exr"
    assert main(["render", "gray_direct", "--target-error", "0.1", "--spp", "8",
                 "--variant", "llvm_ad_rgb", "-o", str(out)]) == 0
    _, meta = exr.read(out)
    assert (meta["spp"], meta["variant"], meta["max_depth"]) == (8, "llvm_ad_rgb", 2)


def test_pass_seeds_stay_32_bit():
    """Regression (fix in render.py): seed·1_000_003 + k overflowed Mitsuba's 32-bit seed."""
    assert render.pass_seed(5000, 3) == (5000 * 1_000_003 + 3) % 2**32 < 2**32
    scene = scenes.load_scene("gray_direct", "llvm_ad_mono", res=8)
    result = render.render_scene(scene, 2, seed=5000, passes=2)
    assert np.isfinite(result.image).all()


# --- step 5: model and sampling -------------------------------------------------------------------

POINT_LIT = """
<integrator type="path"><integer name="max_depth" value="8"/></integrator>
<sensor type="perspective"><float name="fov" value="30"/>
  <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
  <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
  <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/>
    <rfilter type="gaussian"/></film></sensor>
<bsdf type="phong" id="p"><rgb name="diffuse_reflectance" value="0.5, 0.3, 0.2"/>
  <rgb name="specular_reflectance" value="0.3"/><float name="exponent" value="20"/></bsdf>
<shape type="sphere"><ref id="p"/></shape>
<emitter type="point"><point name="position" x="2" y="3" z="4"/>
  <rgb name="intensity" value="20"/></emitter>
"""


def test_plan_prices_models_and_sampling(plans):
    """Every plan states its render (model, sampling) and the priced options behind it; at
    depth > 2 no cheaper exact model exists and it says so."""
    for name, p in plans.items():
        assert p.render.model in ("path", "direct", "whitted")
        assert p.render.sampling in ("uniform", "adaptive")
        assert p.render.seconds > 0 and p.render.spp >= 1
        assert any(r.startswith("priced") for r in p.reasons)
        assert any(r.startswith("chosen:") for r in p.reasons)
        assert p.uses_wavefront == (p.render.model != "path" or p.render.sampling == "adaptive")
    assert plans["cornell_phong"].render.model == "path"
    assert any("no cheaper exact model" in r for r in plans["cornell_phong"].reasons)
    assert any("whitted (radiance units) not considered" in r
               for r in plans["gray_direct"].reasons)


def test_whitted_is_priced_when_every_light_is_a_point_light(tmp_path):
    p = planner.plan(_write(tmp_path, POINT_LIT), PlanOptions(TARGET))
    assert p.max_depth == 2
    priced = next(r for r in p.reasons if r.startswith("priced"))
    assert "whitted, uniform" in priced and "whitted, adaptive" in priced
    assert any(r.startswith("direct-only transport") for r in p.reasons)


def test_whitted_radiance_is_path_at_depth_2_under_point_lights(tmp_path, variant_llvm_rgb):
    """The exactness the planner relies on: with only point lights, whitted in radiance units
    and path at max_depth 2 have the same expected image.  Per-channel image means of 8-pass
    renders, Welch-style z against the two standard errors, Sidak over 3 channels."""
    scene = scenes.load_scene(_write(tmp_path, POINT_LIT), "llvm_ad_rgb")
    w = render.render_scene(scene, 64, seed=1, passes=8, integrator=mi.load_dict(
        {"type": "whitted", "units": "radiance", "max_depth": 2}))
    p = render.render_scene(scene, 64, seed=2, passes=8,
                            integrator=mi.load_dict({"type": "path", "max_depth": 2}))
    (mw, sw), (mp, sp) = w.mean_and_stderr(), p.mean_and_stderr()
    z = np.abs(mw - mp) / np.sqrt(sw ** 2 + sp ** 2)
    assert np.all(z <= stats.t_critical(7, stats.ALPHA, 3)), (mw, mp)


def test_cli_render_planned_wavefront(tmp_path, capsys):
    """A plan that renders through phonglab.engine.adaptive (another model or adaptive sampling)
    writes the image, its stderr and the spp map, and reports the achieved or estimated error."""
    scene = _write(tmp_path, POINT_LIT)
    out = tmp_path / "pl.exr"
    assert main(["render", scene, "--target-error", "0.05", "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "chosen:" in text and "error:" in text
    _, meta = exr.read(out)
    assert meta["max_depth"] == 2 and meta["target_error"] == 0.05
    if meta["planned"]["model"] != "path" or meta["planned"]["sampling"] == "adaptive":
        assert (tmp_path / "pl.spp.exr").is_file()


def test_pilot_keeps_its_samples_per_image_on_large_films():
    """64 spp up to 64² pixels, then 64·64² samples per image, never below 4 spp, in at most
    4 whole passes of at least 1 spp (each pass of a Python integrator is traced anew)."""
    from phonglab.planner.pilot import pilot_size

    assert pilot_size(32 * 32) == (64, 4) and pilot_size(64 * 64) == (64, 4)
    assert pilot_size(80 * 80) == (40, 4)
    assert pilot_size(128 * 128) == (16, 4) and pilot_size(256 * 256) == (4, 4)
    assert pilot_size(1024 * 1024) == (4, 4)
    for n in (100, 5000, 9000, 10 ** 6):
        spp, passes = pilot_size(n)
        assert 2 <= passes <= planner.PILOT_PASSES and spp % passes == 0 and spp >= 4


# --- the one-render depth ladder (planner/ladder.py) ---------------------------------------------

@pytest.mark.parametrize("name,variant", [("cornell_phong", "llvm_ad_rgb"),
                                          ("glass_slab", "llvm_ad_rgb"),
                                          ("gray_room", "llvm_ad_mono")])
def test_depth_ladder_is_path_at_every_depth(name, variant):
    """Expectation: the ladder's image at depth d is Mitsuba's path at max_depth d and its full
    image path at -1 -- sample for sample with the same seed (the ladder draws the sampler's
    dimensions in path.cpp's order), so up to float rounding of the sums, not just within MC
    error; glass_slab covers delta chains, gray_room a mono variant."""
    from phonglab.planner import ladder

    info = scenes.inspect_scene(name, **RES)
    with runtime.quiet_mitsuba():
        scene = scenes.load_scene(info.path, variant, **RES)
    depths = (1, 2, 3, 5, 8)
    got = render.render_scene(scene, 8, seed=3, integrator=ladder.ladder(depths, info)).image
    full, by_depth = ladder.split(got[None], depths)
    for d, img in [(-1, full[0])] + [(d, by_depth[d][0]) for d in depths]:
        want = render.render_scene(scene, 8, seed=3,
                                   integrator=scenes.path_integrator(d, info)).image
        assert img.shape == want.shape
        np.testing.assert_allclose(img, want, rtol=1e-4, atol=1e-5, err_msg=f"depth {d}")


def test_one_kernel_pilot_measures_what_per_depth_renders_measure(monkeypatch):
    """The pilot's depth search from ladder renders (plus one for the weights) gives the same
    b(d), energy and n(1) as path renders at each depth with the same seeds, in fewer renders:
    the first stage's depths against one path render per depth with the first pilot's seeds,
    a later stage's against a full-depth and a depth-d path render with that stage's seed
    (each later stage draws samples of its own, which the planned render reuses)."""
    from phonglab.planner import ladder, pilot

    info = scenes.inspect_scene("cornell_phong", **RES)
    with runtime.quiet_mitsuba():
        scene = scenes.load_scene(info.path, "llvm_ad_rgb", **RES)
    one = pilot.Pilot(scene, info, 16, 8, 1)
    one.second_depths.clear()  # its second pilot's estimate is pooled in (tested below)
    one.search_depth(ALLOWED)
    monkeypatch.setattr(ladder, "applies", lambda info: False)
    per = pilot.Pilot(scene, info, 16, 8, 1)
    assert one.one_kernel and not per.one_kernel
    assert one.renders <= 4  # weights, stages 1-2, the bisection gap
    later = 0
    for a in one.depths():
        seed = one.depth_passes[a.depth][1] if a.depth > 0 else one.seed
        if seed == one.seed:
            b = per.measure(a.depth)
        else:
            later += 1
            full, imgs = per._render(-1, seed), per._render(a.depth, seed)
            bias2 = pilot.depth_bias2(full - imgs, one.weight)
            energy = float((full - imgs).mean(axis=0).sum()) / float(full.mean(axis=0).sum())
            b = pilot.DepthSample(a.depth, math.sqrt(max(bias2, 0.0)), energy,
                                  per.noise_per_sample(imgs))
        for x, y in ((a.bias, b.bias), (a.energy_omitted, b.energy_omitted),
                     (a.noise_per_sample, b.noise_per_sample)):
            assert x == pytest.approx(y, rel=1e-3, abs=1e-6), a.depth
    assert later >= 1   # cornell_phong needs a depth beyond the first stage


def test_depth_bias_is_unbiased_and_pure_noise_is_not_bias():
    """b² = mean[((mean_k D)² − var_k(D)/P)·w] estimates mean(μ²·w): with D = μ + N(0, 1) in
    4 passes over 40 000 values, within z·SE (SE from the per-value terms, Šidák over the
    two cases) of μ²·w; μ = 0 gives 0 (the plug-in (mean_k D)² alone would give w/P)."""
    from phonglab.planner.pilot import depth_bias2

    rng = np.random.default_rng(7)
    z = stats.z_critical(stats.ALPHA, 2)
    w = np.full((100, 100, 4), 2.0)
    for mu in (0.0, 0.3):
        diff = mu + rng.standard_normal((4, 100, 100, 4))
        m, v = diff.mean(axis=0), diff.var(axis=0, ddof=1) / 4
        terms = (m * m - v) * w
        se = terms.std(ddof=1) / math.sqrt(terms.size)
        assert depth_bias2(diff, w) == pytest.approx(float(terms.mean()))
        assert abs(depth_bias2(diff, w) - mu * mu * 2.0) <= z * se


def test_one_kernel_pilot_pools_the_second_pilots_depth_images():
    """Depths of the ladder's first stage are measured twice, from the two pilots (the second's
    differences weighted by the first's weights); b² is their mean weighted by samples."""
    from phonglab.planner.pilot import LADDER_STAGES, Pilot, _weights, depth_bias2

    info = scenes.inspect_scene("cornell_phong", **RES)
    with runtime.quiet_mitsuba():
        scene = scenes.load_scene(info.path, "llvm_ad_rgb", **RES)
    pl = Pilot(scene, info, 16, 8, 1, stratified=scenes.sensor_with_sampler(info, "multijitter"))
    assert sorted(pl.second_depths) == list(LADDER_STAGES[0]) and pl.second_spp == 16
    first, second = dict(pl.ladder_images), dict(pl.second_depths)
    for d in LADDER_STAGES[0]:
        b1 = depth_bias2(pl.full - first[d][1], pl.weight)
        b2 = depth_bias2(pl.second - second[d], _weights(pl.full))
        want = (16 * b1 + 16 * b2) / 32
        assert pl.measure(d).bias == pytest.approx(math.sqrt(max(want, 0.0)), rel=1e-9)
        assert d not in pl.second_depths
    assert pl.measure(6).bias >= 0  # later stages: the first pilot alone


def test_pooled_pilot_sees_the_rare_bounces_of_the_sphere_row():
    """nb_sphere_row at 512×128 (E = 0.005, budget b <= 0.00125): paths of 5 and 6 segments
    (between neighbouring spheres, at their silhouettes) carry b(4) = 0.0021 (a pilot of
    64 spp, two seeds: 0.0021, 0.0022).  The default pilot's 4 passes of 1 spp alone put it at
    3e-6 to 0.003 over ten seeds, six of them under the budget, and the plan chose depth 4 and
    missed E by 6 %; pooled with the second pilot (16 spp) the plan must find depth 4 short."""
    params = {"width": 512, "height": 128}
    p = planner.plan("nb_sphere_row", PlanOptions(0.005, params=params))
    b4 = next(d for d in p.pilot.depths if d.depth == 4)
    assert b4.bias > planner.BIAS_FRACTION * 0.005
    assert p.max_depth > 4


def test_ladder_work_counts_the_casts_of_a_truncated_path():
    """10 paths that found 1 vertex (2 casts) and 10 that found 3 (4 casts): unbounded 3 casts
    a sample; at max_depth 2 every path casts 2, at 3: (2 + 3)/2."""
    from phonglab.planner import ladder

    lengths = [0, 10, 0, 10]
    assert ladder.work(lengths, -1) == 3.0
    assert ladder.work(lengths, 2) == 2.0
    assert ladder.work(lengths, 3) == 2.5
    assert ladder.work(lengths, 64) == 3.0


def test_ladder_histograms_the_length_of_every_sample():
    """One count per sample traced; cornell_phong (closed box, roulette from depth 5) has
    paths of every length up to 5 and fewer beyond."""
    from phonglab.planner import ladder

    info = scenes.inspect_scene("cornell_phong", **RES)
    with runtime.quiet_mitsuba():
        scene = scenes.load_scene(info.path, "llvm_ad_rgb", **RES)
    integ = ladder.ladder((1, 2), info)
    result = render.render_scene(scene, 8, seed=2, passes=2, integrator=integ)
    lengths = np.array(integ.lengths, dtype=np.int64)
    assert lengths.sum() == 8 * result.image.shape[0] * result.image.shape[1]
    assert np.all(lengths[1:6] > 0) and lengths[6:].sum() < lengths[5]
    assert 1.0 < ladder.work(lengths, 4) < 4.0 < ladder.work(lengths, -1)


def test_depth_ladder_stands_in_only_where_it_is_path(tmp_path, variant_llvm_rgb):
    """RGB/mono scenes that show their emitters: yes; hide_emitters or spectral: no."""
    from phonglab.planner import ladder

    assert ladder.applies(scenes.inspect_scene("cornell_phong", **RES))
    hidden = _write(tmp_path, '<integrator type="path"><boolean name="hide_emitters" '
                              'value="true"/></integrator>')
    assert not ladder.applies(scenes.inspect_scene(hidden))
    mi.set_variant("llvm_ad_spectral")
    try:
        assert not ladder.applies(scenes.inspect_scene("cornell_phong", **RES))
    finally:
        mi.set_variant("llvm_ad_rgb")


def test_benchmark_table_names_the_film_of_each_row():
    """Rows of scripts/planner_bench.py: R² films, and W×H where the scene takes width/height."""
    row = {"scene": "s", "res": 128, "target_error": 0.01, "speedup": 1.5, "speedup_min": 1.2,
           "speedup_max": 1.8,
           "default": {"spp": 10, "error": 0.01, "seconds_median": 3.0},
           "planned": {"model": "path", "sampling": "adaptive", "variant": "llvm_ad_mono",
                       "max_depth": 2, "spp": 5.0, "error": 0.0099, "seconds_median": 2.0,
                       "pilot_seconds": 0.5}}
    wide = dict(row, scene="w", params={"width": 512, "height": 128})
    strat = dict(row, scene="m", speedup=1.2, planned=dict(row["planned"], sampling="uniform",
                                                         sampler="multijitter"))
    table = planner.benchmark_table([row, wide, strat])
    assert "| s (128²) | 0.01 |" in table and "| w (512×128) |" in table
    assert "1.50x (1.20-1.80) | 1.50x |" in table
    assert "path uniform (multijitter), llvm_ad_mono" in table
    assert "at least 1.5x on 2 of 3" in table and "at least 0.95x" in table
    held = planner.benchmark_table([row, dict(strat, held_out=True)])
    assert "On the held-out rows: at least 0.95x the default's speed" in held
    # the error promise: achieved / E per seed, ≤ 1.1 E and ≥ 0.8 E
    promise = planner.benchmark.promise_table(
        [dict(row, planned=dict(row["planned"], errors=[0.0099, 0.0115])),
         dict(strat, planned=dict(strat["planned"], errors=[0.0075], reused_spp=32))])
    assert "| s (128²) | adaptive | 0.990, 1.150 | **missed** | met |" in promise
    assert "| m (128²) | uniform + pilot | 0.750 | met | **missed** |" in promise


def test_equal_error_speedup_only_ever_lowers_the_raw_ratio():
    """A planned error above E costs (E/e)²; a default below E costs (e/E)²; never a bonus."""
    row = {"target_error": 0.05, "speedup": 2.0, "default": {"error": 0.05},
           "planned": {"error": 0.05}}
    assert benchmark.equal_error_speedup(row) == pytest.approx(2.0)
    over = dict(row, planned={"error": 0.055})
    assert benchmark.equal_error_speedup(over) == pytest.approx(2.0 * (0.05 / 0.055) ** 2)
    under = dict(row, default={"error": 0.045})
    assert benchmark.equal_error_speedup(under) == pytest.approx(2.0 * (0.045 / 0.05) ** 2)
    lucky = dict(row, default={"error": 0.06}, planned={"error": 0.04})  # both in our favour
    assert benchmark.equal_error_speedup(lucky) == pytest.approx(2.0)


def test_error_model_recovers_bias_and_noise_and_the_spp_at_e():
    """e(N)² = b² + c/N: exact points give (b², c) back; the spp solving e(N) = E follows,
    and a bias at or above E leaves no spp (inf).  One point, or a slope noise made
    negative, falls back to the noise-only model through the point of most samples."""
    b2, c = 0.035 ** 2, 1.3
    points = [(n, math.sqrt(b2 + c / n)) for n in (64, 800, 3200)]
    fb2, fc = benchmark.fit_error_model(points)
    assert fb2 == pytest.approx(b2, rel=1e-9) and fc == pytest.approx(c, rel=1e-9)
    n = benchmark.spp_for_error(fb2, fc, 0.05)
    assert math.sqrt(b2 + c / n) == pytest.approx(0.05)
    assert n > 800 * (math.sqrt(b2 + c / 800) / 0.05) ** 2   # the noise-only rule stops short
    assert benchmark.spp_for_error(0.06 ** 2, c, 0.05) == math.inf
    assert benchmark.fit_error_model([(100, 0.1)]) == (0.0, pytest.approx(1.0))
    assert benchmark.fit_error_model([(100, 0.1), (400, 0.11)]) == (
        0.0, pytest.approx(400 * 0.0121))


# --- the stratified sampler (planner step 5, render's sampler) ----------------------------------

def test_sensor_with_sampler_keeps_the_camera_and_film():
    info = scenes.inspect_scene("gray_direct", **RES)
    assert info.sampler == "independent" and "<sensor" in info.sensor_xml
    with runtime.quiet_mitsuba():
        scene = scenes.load_scene("gray_direct", "llvm_ad_rgb", **RES)
    sensor = scenes.sensor_with_sampler(info, "multijitter")
    assert sensor.sampler().class_name() == "MultijitterSampler"
    assert list(sensor.film().size()) == list(scene.sensors()[0].film().size())
    assert render.pass_spps(scene, 40, 8, sensor) == [6] * 8   # 5 -> 2 x 3 strata
    assert render.pass_spps(scene, 40, 8) == [5] * 8
    # Unbiased: the image sums of both samplers agree within their standard errors
    # (expectation: equal; 4 sigma, alpha ~ 6e-5).
    mj = render.render_scene(scene, 256, seed=3, passes=8, sensor=sensor)
    ind = render.render_scene(scene, 256, seed=4, passes=8)
    diff = float(mj.image.sum() - ind.image.sum())
    se = math.sqrt(float((mj.stderr.astype(np.float64) ** 2).sum()
                         + (ind.stderr.astype(np.float64) ** 2).sum()))
    assert abs(diff) < 4 * se, (diff, se)
    # ... and the stratified one is the less noisy (gray_direct: ~3x lower variance at 32 spp).
    assert float((mj.stderr ** 2).sum()) < 0.7 * float((ind.stderr ** 2).sum())


def test_a_sensor_that_cannot_stand_alone_is_one_sentence(tmp_path):
    path = _write(tmp_path, '<shape type="sphere"/>')
    info = scenes.inspect_scene(path)
    with pytest.raises(scenes.SceneError, match="no top-level <sensor>"):
        scenes.sensor_with_sampler(info, "multijitter")


def test_stratification_gain_recovers_a_known_ratio():
    """Synthetic passes: independent ones of s_i samples with per-sample variance sigma^2,
    stratified ones whose pass variance is sigma^2/(s_s g); the estimate is g within 5 of its
    standard errors (chi-square: sqrt(2/dof) relative, 1 dof per value with 2 passes)."""
    rng = np.random.default_rng(7)
    shape, sigma2, s_i, s_s, g = (64, 64, 3), 0.04, 2, 8, 3.0
    indep = 0.5 + rng.normal(0, math.sqrt(sigma2 / s_i), (8,) + shape)
    strat = 0.5 + rng.normal(0, math.sqrt(sigma2 / (s_s * g)), (2,) + shape)
    w = np.full(shape, 1.0)
    est = planner.pilot.stratification_gain(indep, s_i, w, strat, s_s, w)
    rel_se = math.sqrt(2 / strat[0].size + 2 / (7 * indep[0].size))
    assert abs(est / g - 1) < 5 * rel_se, est


@given(n=st.integers(1, 20000), min_pass=st.sampled_from([1, 8, 16, 64]),
       a=st.floats(0.0, 0.05), b=st.floats(1e-4, 1.0))
def test_stratified_layout_holds_the_samples_in_cheap_passes(n, min_pass, a, b):
    """At least n samples in 2-8 passes of a count >= the pilot's pass size whose multijitter
    grid has power-of-two sides; no layout of that kind is predicted faster."""
    choice = planner.choice
    p, s = choice.stratified_layout(n, min_pass, a, b)
    assert p * s >= n and 2 <= p <= 8 and s >= min_pass and s in choice.CHEAP_PASS_SPP
    rows = math.isqrt(s)
    cols = -(-s // rows)
    assert rows * cols == s and rows & (rows - 1) == 0 and cols & (cols - 1) == 0
    for c in (c for c in choice.CHEAP_PASS_SPP if c >= min_pass):
        q = max(2, -(-n // c))
        if q <= 8:
            assert p * a + b * p * s <= q * a + b * q * c + 1e-12


def test_stratified_layout_examples():
    """The bench's plans: gray_direct 256² needed 63 spp (was 2 passes of 35 = 5 x 7 strata,
    1.35x independent's time per sample), cornell_phong 280 (was 8 of 35)."""
    layout = planner.choice.stratified_layout
    assert layout(63, 8, 0.002, 0.005) == (4, 16)
    assert layout(66, 8, 0.002, 0.005) == (5, 16)
    assert layout(40, 8, 0.002, 0.005) == (5, 8)
    assert layout(280, 8, 0.002, 0.005) == (5, 64)
    assert layout(10 ** 6, 8, 0.002, 0.005) == (8, 125000)


def test_plans_price_the_stratified_sampler_and_its_render_meets_the_target(plans):
    """Each plan measures multijitter's gain and prices it; at E = 0.002 gray_direct (direct
    light, ~3-5x lower variance stratified) chooses it, combined with the pilot's samples,
    and the render the plan runs (execute.render_plan) reaches the target against the
    converged reference; so does the plan's standalone uniform render (render_kwargs)."""
    from phonglab.planner import execute

    for name, p in plans.items():
        assert any(r.startswith("sampler: multijitter") for r in p.reasons), name
    target = 0.002   # (at 0.003 the pilot's own samples nearly suffice: 2 spp more)
    p = planner.plan("gray_direct", PlanOptions(target, params=RES))
    assert p.render.sampler == "multijitter" and p.reused, p.summary()
    assert p.render.spp / p.render.passes >= planner.pilot.STRATIFIED_PASS_SPP
    ref = references.reference("gray_direct", max(1024, 16 * p.uniform.spp), params=RES)
    errs = [execute.render_plan(p, seed=100 + seed, reference=ref).error.achieved
            for seed in range(3)]
    # the gain is measured on 8-spp passes and these hold more: the error errs low
    assert max(errs) <= 1.15 * target, (errs, p.summary())
    kw = p.render_kwargs()   # alone: the uniform spp of independent samples
    assert kw == {"spp": p.uniform.spp, "variant": p.variant, "max_depth": p.max_depth,
                  "passes": p.uniform.passes}
    info = scenes.inspect_scene("gray_direct", **RES)
    scene = scenes.load_scene("gray_direct", p.variant, **RES)
    result = render.render_scene(scene, kw["spp"], seed=200, passes=kw["passes"],
                                 integrator=scenes.path_integrator(p.max_depth, info))
    assert metrics.relative_rmse(result.image, ref.image, ref_stderr=ref.stderr) <= 1.15 * target


# --- the pilot's samples reused by the render ----------------------------------------------------

def _fake_render(rng, mean, sigma, spp, passes):
    """A RenderResult of ``passes`` Gaussian pass images of ``spp`` samples in all, each
    sample of standard deviation ``sigma`` about ``mean``."""
    per = spp // passes
    imgs = mean + rng.standard_normal((passes,) + mean.shape) * sigma / math.sqrt(per)
    merge = render.PassMerge(per * passes, passes)
    for img in imgs:
        merge.add(img, per)
    return merge.result(0.0, [])


def test_combined_renders_are_unbiased_with_the_error_their_weights_predict():
    """Three independent renders of one image (different noise and samples) combined with
    inverse-variance weights: the weights are ∝ n_j/V_j, the image is unbiased and its error
    is what 1/Σ n_j/V_j predicts.  Expectation: mean over pixels of (x̂ − μ)²/Var x̂ is 1,
    with standard error √(2/pixels) for Gaussian noise; tolerance z(α, 2)·SE (Šidák over
    the two checks)."""
    rng = np.random.default_rng(3)
    mean = rng.uniform(0.2, 2.0, size=(64, 64, 3))
    w = 1.0 / (mean ** 2 + metrics.REL_EPS)
    parts = [_fake_render(rng, mean, s, n, p) for s, n, p in ((0.5, 16, 4), (0.2, 16, 2),
                                                              (1.0, 48, 8))]
    prec = [render.precision(p, w) for p in parts]
    out = render.combine_renders(parts, prec)
    alpha = [c["weight"] for c in out.metadata["combined"]]
    assert alpha == pytest.approx([p / sum(prec) for p in prec])
    var = sum(a * a * p.stderr.astype(np.float64) ** 2 for a, p in zip(alpha, parts))
    z = stats.z_critical(stats.ALPHA, 2)
    # the true variance of x̂ (σ_j²/n_j per part), not the estimated one: the check is of the
    # combination, not of the pass estimates
    true_var = sum(a * a * s * s / n for a, (s, n) in zip(alpha, ((0.5, 16), (0.2, 16), (1.0, 48))))
    ratio = float(np.mean((out.image - mean) ** 2 / true_var))
    assert abs(ratio - 1.0) <= z * math.sqrt(2.0 / mean.size)
    assert np.allclose(out.stderr.astype(np.float64) ** 2, var, rtol=1e-5)
    assert out.metadata["combined_noise"] == pytest.approx(1.0 / math.sqrt(sum(prec)))
    assert out.pass_spp == [s for p in parts for s in p.pass_spp]


def test_weights_from_other_samples_measure_a_firefly_render_honestly():
    """A render whose rare samples are bright (a firefly in 1 of 64 samples): its precision
    with weights from its own image overstates it (the firefly weighs itself down); with the
    true weights it matches the error actually made.  This is why the pilot measures every
    reusable render with another render's weights."""
    rng = np.random.default_rng(5)
    shape, passes, per = (128, 128, 1), 4, 4
    samples = np.where(rng.random((passes, per) + shape) < 1 / 64, 32.0, 0.5)   # mean 1.0
    mean = np.full(shape, 0.5 * 63 / 64 + 32.0 / 64)
    merge = render.PassMerge(passes * per, passes)
    for k in range(passes):
        merge.add(samples[k].mean(axis=0), per)
    result = merge.result(0.0, [])
    true = float(np.mean((result.image - mean) ** 2 / (mean ** 2 + metrics.REL_EPS)))
    honest = 1.0 / render.precision(result, 1.0 / (mean ** 2 + metrics.REL_EPS))
    own = 1.0 / render.precision(result, 1.0 / (result.image.astype(np.float64) ** 2
                                                 + metrics.REL_EPS))
    assert own < 0.6 * true and abs(honest / true - 1) < 0.15


def test_a_planned_render_reuses_the_pilot_and_reaches_the_target():
    """gray_room at 32², E = 0.006: the plan combines its render with the pilot's renders
    (other seeds), so it renders fewer samples than its uniform spp, and the combination
    reaches E against the converged reference (bias ≤ b(d) + noise; tolerance 1.15 E, as
    the stratified plan's test) on three render seeds.  (How close the estimate comes to the
    achieved error is the bench's to measure: on 1024 pixels of a room with fireflies the
    true error of one render scatters by ±20 % about its expectation.)"""
    from phonglab.planner import execute

    target = 0.006
    p = planner.plan("gray_room", PlanOptions(target, params=RES))
    assert p.reused is not None and p.reused_spp > 0, p.summary()
    assert math.ceil(p.render.spp) < p.uniform.spp
    assert any(r.startswith("reuse:") for r in p.reasons)
    ref = references.reference("gray_room", 4096, params=RES)
    for seed in range(3):
        done = execute.render_plan(p, seed=100 + seed, reference=ref)
        assert "combined" in done.result.metadata
        assert done.error.achieved <= 1.15 * target, (done.error, p.summary())


def test_a_render_seed_among_the_pilots_renders_alone():
    """A render whose seed is one of the pilot's would count the same samples twice: it
    renders the plan's uniform spp alone (standalone plan), and says so."""
    from phonglab.planner import execute

    p = planner.plan("gray_room", PlanOptions(0.03, params=RES, seed=4))
    assert p.pilot.seed == 4 + planner.PILOT_SEED == 5   # the plan's render seed is 4
    assert p.reused is not None and p.repeats_pilot(5) and not p.repeats_pilot(4)
    done = execute.render_plan(p, seed=6)
    assert "combined" not in done.result.metadata
    assert sum(done.result.pass_spp) == p.uniform.spp
    assert "the render's seed is one of the pilot's" in done.plan.reasons[-1]


def test_the_pilots_renders_never_share_seeds(monkeypatch):
    """Every pilot render that the planned render may be combined with has a seed of its own
    (a later ladder stage too), all within pilot_seed .. pilot_seed + PILOT_SEEDS, so the
    render seed the plan is made for (PlanOptions.seed, pilot seed − 1) repeats none of
    them."""
    seeds = []
    real = render.render_scene

    def spy(scene, spp, seed=0, **kw):
        seeds.append(seed)
        return real(scene, spp, seed=seed, **kw)

    monkeypatch.setattr(render, "render_scene", spy)
    p = planner.plan("cornell_phong", PlanOptions(0.05, params=RES, seed=39))
    assert len(seeds) == len(set(seeds)), seeds
    assert all(40 <= s <= 40 + planner.pilot.PILOT_SEEDS for s in seeds)
    assert not p.repeats_pilot(39)


def test_a_render_cheaper_than_the_pilot_is_planned_straight_away(monkeypatch):
    """gray_room at 32², E = 0.05: the pilot's two full-depth renders already hold most of
    what the image needs, the rest costs less than the first pilot render did, so the plan
    skips the depth search and the time model (no path render of the pilot), says so, and
    renders path at full depth (unbiased) combined with the pilot's renders; the result
    reaches E against the converged reference (tolerance 1.15 E, three seeds)."""
    from phonglab.planner import execute

    calls = []
    real = render.render_scene
    monkeypatch.setattr(render, "render_scene",
                        lambda *a, **kw: calls.append(kw.get("integrator")) or real(*a, **kw))
    target = 0.05
    p = planner.plan("gray_room", PlanOptions(target, params=RES, straight=True))
    assert any(r.startswith("straight:") for r in p.reasons), p.summary()
    assert p.max_depth == -1 and p.uniform.predicted_bias == 0.0 and p.reused is not None
    assert len(calls) == 2   # the two pilot renders, nothing else
    monkeypatch.setattr(render, "render_scene", real)
    full = planner.plan("gray_room", PlanOptions(target, params=RES, straight=False))
    assert not any(r.startswith("straight:") for r in full.reasons) and full.max_depth > 0
    ref = references.reference("gray_room", 4096, params=RES)
    for seed in range(3):
        done = execute.render_plan(p, seed=100 + seed, reference=ref)
        assert done.error.achieved <= 1.15 * target, (done.error, p.summary())


def test_a_rest_of_a_few_first_renders_goes_straight(monkeypatch):
    """gray_room at 32², E = 0.008: the rest of the image needs more spp than the first pilot
    render took (it does not run the whole pilot then) but at most
    STRAIGHT_RENDERS times as many, as the straight reason says: the plan goes straight;
    with the threshold at one first render the depth search runs."""
    import re

    p = planner.plan("gray_room", PlanOptions(0.008, params=RES, straight=True))
    reason = next((r for r in p.reasons if r.startswith("straight:")), None)
    assert reason is not None and p.max_depth == -1, p.summary()
    rest = int(re.search(r"needs (\d+) more spp", reason).group(1))
    assert p.pilot.spp < rest <= planner.planning.STRAIGHT_RENDERS * p.pilot.spp
    assert f"{planner.planning.STRAIGHT_RENDERS} first renders or less" in reason
    monkeypatch.setattr(planner.planning, "STRAIGHT_RENDERS", 1)
    full = planner.plan("gray_room", PlanOptions(0.008, params=RES, straight=True))
    assert not any(r.startswith("straight:") for r in full.reasons) and full.max_depth > 0


@pytest.mark.parametrize("extra", [[], ["--adaptive", "--target-noise", "0.1"]],
                         ids=["alone", "adaptive"])
def test_full_pilot_without_a_target_error_is_one_sentence(capsys, extra):
    """--full-pilot belongs to the planner: alone (or with --adaptive) it is refused, exit 2."""
    assert main(["render", "gray_direct", "--full-pilot", *extra]) == 2
    assert "--full-pilot is about the planner's pilot" in capsys.readouterr().err


def _planner_bench_module():
    """scripts/planner_bench.py, imported from its file (it is a script, not a module)."""
    import importlib.util
    from pathlib import Path
    path = Path(__file__).resolve().parents[1] / "scripts" / "planner_bench.py"
    spec = importlib.util.spec_from_file_location("planner_bench", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _bench_row(scene, res, **extra):
    return {"scene": scene, "res": res, "target_error": 0.01, "speedup": 1.0, "speedup_min": 0.9,
            "speedup_max": 1.1, "default": {"spp": 10, "error": 0.01, "seconds_median": 3.0},
            "planned": {"model": "path", "sampling": "uniform", "variant": "llvm_ad_rgb",
                        "max_depth": 8, "spp": 10.0, "error": 0.01, "seconds_median": 3.0,
                        "pilot_seconds": 0.5, "reasons": []}, **extra}


def test_planner_bench_merge_keeps_the_rows_a_run_does_not_redo(tmp_path):
    """--merge: rows of other scenes or resolutions stay, a redone (scene, res) is replaced,
    and no file yet means just the fresh rows."""
    pb = _planner_bench_module()
    out = tmp_path / "p.json"
    assert pb.merged_rows(out, [_bench_row("a", 512)]) == [_bench_row("a", 512)]
    out.write_text(json.dumps([_bench_row("a", 512, speedup=2.0), _bench_row("b", 512),
                               _bench_row("a", 256)]))
    merged = pb.merged_rows(out, [_bench_row("a", 512, speedup=3.0)])
    assert [(r["scene"], r["res"], r["speedup"]) for r in merged] == \
        [("b", 512, 1.0), ("a", 256, 1.0), ("a", 512, 3.0)]


def test_planner_bench_refuses_bad_input_before_any_work(capsys):
    """An unknown scene, or an --out naming a folder: one sentence, exit 2, no render."""
    pb = _planner_bench_module()
    assert pb.main(["no_such_scene", "--out", "/nonexistent/p.json"]) == 2
    assert "unknown scene(s) no_such_scene" in capsys.readouterr().err
    # an --out that names a folder is refused before any render, in one sentence
    assert pb.main(["gray_direct", "--out", "/tmp/"]) == 2
    err = capsys.readouterr().err
    assert "ends in '/', which names a folder" in err and len(err.strip().splitlines()) == 1


def test_benchmarks_md_shows_the_512_rows_apart_with_their_date_and_cost(tmp_path):
    """BENCHMARKS.md's planner section: the make bench rows, then the 512² rows make bench does
    not rerun, with their dates and what they cost (bench_seconds summed); either alone too."""
    from phonglab.bench import report
    from phonglab.bench.report_data import RunData

    def section():
        data = RunData(out=tmp_path, rel=".", run={}, results=[], stab=[], ratios=[], jit=[],
                       quick=None)
        return "\n".join(report.planner_section(data))

    assert section() == ""
    (tmp_path / report.PLANNER_LARGE).write_text(json.dumps(
        [_bench_row("a", 512, date="2026-12-06", bench_seconds=600.0,
                    reference={"spp": 1024, "seconds": 120.0}),
         _bench_row("b", 512, date="2026-12-07", bench_seconds=1200.0, speedup=0.5)]))
    text = section()
    assert "### At 512²" in text and "measured 2026-12-06, 2026-12-07" in text
    assert "these 2 rows took 30 min, 2 of them rendering references" in text
    assert "| a (512²) |" in text
    assert "* **b** (512): 0.50x at equal error" in text and "At 128² and 256²" not in text
    (tmp_path / "planner.json").write_text(json.dumps([_bench_row("a", 128)]))
    text = section()
    assert text.index("| a (128²) |") < text.index("### At 512²") < text.index("| a (512²) |")
