"""What a render is given: scenes that cannot be rendered (no sensor, films of 0 pixels or too large
for memory, load errors named for what went wrong), ``--max-depth`` keeping the scene's
integrator, seeds within Mitsuba's 32 bits, films of other formats, AOV and particle-tracing
integrators (phonglab.engine.render, phonglab.engine.scenes)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from phonglab import cli, stats
from phonglab.engine import exr
from phonglab.engine.render import render_scene
from phonglab.engine.scenes import load_scene
from phonglab.errors import SceneError

from helpers import FILM, WHITTED_NO_DEPTH_DEFAULT, fails_in_one_sentence as _fails_in_one_sentence, write as _write


# --- --max-depth keeps the scene's integrator ---------------------------------------------------

def test_max_depth_applies_to_the_scenes_own_integrator(tmp_path, capsys):
    scene = _write(tmp_path, "w.xml", WHITTED_NO_DEPTH_DEFAULT)
    out = tmp_path / "w.exr"
    assert cli.main(["render", str(scene), "--spp", "1", "--max-depth", "3", "-o", str(out)]) == 0
    meta = exr.read(out)[1]
    assert meta["max_depth"] == 3 and "Whitted" in meta["integrator"], meta


def test_max_depth_is_refused_for_an_integrator_without_one(tmp_path, capsys):
    scene = _write(tmp_path, "d.xml", WHITTED_NO_DEPTH_DEFAULT.replace(
        '<integrator type="whitted"><string name="units" value="graphics"/></integrator>',
        '<integrator type="direct"/>'))
    _fails_in_one_sentence(capsys, ["render", str(scene), "--max-depth", "3", "-o",
                                    str(tmp_path / "d.exr")], "'direct' integrator", "max_depth")
    assert not (tmp_path / "d.exr").exists()


# --- scenes that cannot be rendered, and errors named for what went wrong ----------------------

def test_a_scene_without_a_sensor_is_one_sentence(tmp_path, capsys):
    scene = _write(tmp_path, "s.xml", '<scene version="3.0.0"><shape type="sphere"/>'
                                      '<emitter type="constant"/></scene>')
    _fails_in_one_sentence(capsys, ["render", str(scene), "-o", str(tmp_path / "s.exr")],
                           "no <sensor>")


@pytest.mark.parametrize("res, words", [(0, "0 x 0 pixels"), (20000, "GiB of memory")])
def test_impossible_films_are_refused_before_allocation(variant_llvm_rgb, res, words):
    scene = load_scene("gray_direct", res=res)
    with pytest.raises(SceneError, match=words):
        render_scene(scene, 1)


@pytest.mark.parametrize("body, params, words", [
    ('<bsdf type="phong"><float name="exponent" value="shiny"/></bsdf>', {},
     "'shiny' is not a valid floating point value"),
    ('<bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" '
     'value="missing.png"/></texture></bsdf>', {}, "cannot open the file 'missing.png'"),
    ('<bsdf type="diffuse"/>', {"spp": "-3"}, "sample_count = -3"),
    ('<bsdf type="diffuse"/>', {"unused": "1"}, "does not use the parameter(s) unused=1"),
])
def test_load_errors_are_named_for_what_went_wrong(tmp_path, variant_llvm_rgb, body, params, words):
    film = FILM.replace('<film', '<sampler type="independent"><integer name="sample_count" '
                                 'value="$spp"/></sampler><film')
    scene = _write(tmp_path, "e.xml", f'<scene version="3.0.0"><default name="spp" value="4"/>'
                                      f'{film}<shape type="sphere">{body}</shape></scene>')
    with pytest.raises(SceneError) as info:
        load_scene(scene, **params)
    msg = str(info.value)
    assert words in msg and "malformed XML" not in msg and "\n" not in msg, msg


def test_a_plugin_value_error_is_passed_through(tmp_path, capsys):
    scene = _write(tmp_path, "w.xml", WHITTED_NO_DEPTH_DEFAULT.replace(
        '<string name="units" value="graphics"/>',
        '<float name="attenuation_constant" value="-1"/>'))
    _fails_in_one_sentence(capsys, ["render", str(scene), "-o", str(tmp_path / "w.exr")],
                           "whitted: 'attenuation_constant' must be >= 0")


def test_malformed_xml_is_still_called_so(tmp_path, capsys):
    scene = _write(tmp_path, "m.xml", '<scene version="3.0.0"><shape type="sphere"></scene>')
    assert cli.main(["render", str(scene), "-o", str(tmp_path / "m.exr")]) == 2
    assert "malformed XML" in capsys.readouterr().err


def test_the_render_id_ties_image_and_stderr(tmp_path):
    out = tmp_path / "x.exr"
    assert cli.main(["render", "gray_direct", "--spp", "16", "-o", str(out)]) == 0
    image_id = exr.read(out)[1]["render_id"]
    assert exr.read(exr.stderr_path(out))[1]["render_id"] == image_id
    assert np.isfinite(exr.read_image(out)).all()


# --- seeds: Mitsuba's 32-bit range, refused outside it before any work -------------------------

@pytest.mark.parametrize("command", [["render", "gray_direct"], ["check", "--only", "snell"],
                                     ["validate", "diffuse", "--quick"],
                                     ["compare-models", "gray_direct"]])
@pytest.mark.parametrize("bad", ["-1", str(1 << 32), "1e3"])
def test_a_seed_outside_32_bits_is_refused_before_any_work(command, bad, capsys):
    """-1 and 2³² − 1 would render the same image (pass seeds are taken mod 2³²) under
    different recorded seeds, and `validate --seed -1` would fail seven topics: both are bad
    input, exit 2."""
    with pytest.raises(SystemExit) as info:
        cli.main([*command, "--seed", bad])
    assert info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert "argument --seed: the seed must" in err and "Traceback" not in err, err


def test_distinct_seeds_give_distinct_first_pass_seeds():
    """pass_seed(s, 0) = s·1_000_003 mod 2³² is a bijection of 0..2³² − 1 (the factor is odd):
    no two accepted seeds share their first pass."""
    from phonglab.engine.render import pass_seed

    seeds = np.random.default_rng(5).integers(0, 1 << 32, 200_000, dtype=np.uint64)
    seeds = np.unique(np.concatenate([seeds, [0, 1, (1 << 32) - 1]]))
    mapped = {pass_seed(int(s), 0) for s in seeds}
    assert len(mapped) == len(seeds) and all(0 <= m < 1 << 32 for m in mapped)


# --- what real scenes carry: film formats, AOV and particle-tracing integrators ----------------

CONTENT = """<scene version="3.0.0">
  {integrator}
  <sensor type="perspective"><transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0"
    up="0, 1, 0"/></transform><film type="hdrfilm"><integer name="width" value="12"/>
    <integer name="height" value="10"/><string name="pixel_format" value="{fmt}"/></film></sensor>
  <shape type="sphere"><bsdf type="diffuse"/></shape>
  <emitter type="point"><point name="position" value="0, 2, 3"/><rgb name="intensity" value="5"/>
  </emitter>
</scene>"""
PATH = '<integrator type="path"/>'
AOV = '<integrator type="aov"><string name="aovs" value="nn:sh_normal"/></integrator>'
AOV_NESTED = ('<integrator type="aov"><string name="aovs" value="dd:depth"/>'
              '<integrator type="path" name="p"/></integrator>')
PTRACER = '<integrator type="ptracer"/>'


def _content(tmp_path, integrator=PATH, fmt="rgb", name="s.xml") -> Path:
    return _write(tmp_path, name, CONTENT.format(integrator=integrator, fmt=fmt))


@pytest.mark.parametrize("fmt, names", [("xyz", ["X", "Y", "Z"]), ("luminance_alpha", ["Y", "A"]),
                                        ("xyza", ["X", "Y", "Z", "A"])])
def test_a_film_of_another_pixel_format_keeps_its_channel_names(variant_llvm_rgb, tmp_path, capsys,
                                                                fmt, names):
    """An xyz or luminance_alpha film is written with its own channels, not as RGB (R, G, B)."""
    import OpenEXR

    out = tmp_path / "x.exr"
    assert cli.main(["render", str(_content(tmp_path, fmt=fmt)), "--spp", "16", "-o",
                     str(out)]) == 0
    for path in (out, exr.stderr_path(out)):
        with OpenEXR.File(str(path)) as f:
            assert sorted(f.channels()) == sorted(names), path
        image, meta = exr.read(path)
        assert meta["channels"] == names and image.shape == (10, 12, len(names))
    rgb = tmp_path / "rgb.exr"
    assert cli.main(["render", str(_content(tmp_path, name="r.xml")), "--spp", "4", "-o",
                     str(rgb)]) == 0
    if len(names) == 3:                    # same shape, other quantities: not comparable
        capsys.readouterr()
        _fails_in_one_sentence(capsys, ["compare", str(out), str(rgb)], "holds channels X, Y, Z")


@pytest.mark.parametrize("fmt", ["rgb", "rgba", "luminance"])
def test_the_usual_films_are_written_as_before(variant_llvm_rgb, tmp_path, fmt):
    out = tmp_path / "x.exr"
    assert cli.main(["render", str(_content(tmp_path, fmt=fmt)), "--spp", "4", "-o",
                     str(out)]) == 0
    image, meta = exr.read(out)
    assert "channels" not in meta and image.shape == {"rgb": (10, 12, 3), "rgba": (10, 12, 4),
                                                      "luminance": (10, 12)}[fmt]


ADAPTIVE = ["--adaptive", "--target-noise", "0.1"]


@pytest.mark.parametrize("integrator, route, needle", [
    (AOV, [], "arbitrary output variables (nn.X, nn.Y, nn.Z)"),
    (AOV_NESTED, [], "arbitrary output variables (p.R, p.G, p.B, p.A, ...)"),
    (AOV, ADAPTIVE, "arbitrary output variables"),
    (PTRACER, ADAPTIVE, "not sampled per pixel"),
], ids=["aov", "aov-nested", "aov-adaptive", "ptracer-adaptive"])
def test_integrators_phonglab_cannot_sample_are_one_sentence(tmp_path, capsys, integrator,
                                                             route, needle):
    """An aov integrator's render (its 4 AOV channels are no RGBA) and --adaptive on it (no
    'error 0, meets the target') or on ptracer (no nanobind TypeError) are one sentence."""
    out = tmp_path / "x.exr"
    _fails_in_one_sentence(capsys, ["render", str(_content(tmp_path, integrator)), "-o", str(out),
                                    *(route or ["--spp", "4"])], needle)
    assert not out.exists()


def test_a_particle_tracer_renders_uniformly(variant_llvm_rgb, tmp_path):
    out = tmp_path / "x.exr"
    assert cli.main(["render", str(_content(tmp_path, PTRACER)), "--spp", "16", "-o",
                     str(out)]) == 0
    assert exr.read(out)[0].shape == (10, 12, 3)


@pytest.mark.parametrize("fmt", ["xyz", "luminance", "rgba"])
def test_adaptive_refuses_a_film_it_would_write_as_rgb(variant_llvm_rgb, tmp_path, capsys, fmt):
    """A luminance film rendered adaptively came out as three channels named R, G, B."""
    _fails_in_one_sentence(capsys, ["render", str(_content(tmp_path, fmt=fmt)), *ADAPTIVE,
                                    "-o", str(tmp_path / "x.exr")],
                           "adaptive sampling writes R, G, B", "pixel_format")


def test_a_wide_film_has_a_bounded_spp_preview(tmp_path):
    """A 4096 x 4 film made a 262144-pixel-wide spp map preview (the preview adds a title,
    a colour bar and labels below the map: 70 pixels, and at least 320 wide)."""
    from PIL import Image

    from phonglab.engine.spp_map import SPP_PNG_MAX_SIDE, write_spp_map_png

    for shape in [(4, 4096), (4096, 4), (3, 9000), (16, 16)]:
        path = write_spp_map_png(tmp_path / "m.png", np.full(shape, 4))
        assert max(Image.open(path).size) <= SPP_PNG_MAX_SIDE + 70, shape


CROP = ('<integer name="crop_offset_x" value="4"/><integer name="crop_offset_y" value="2"/>'
        '<integer name="crop_width" value="6"/><integer name="crop_height" value="5"/>'
        '<rfilter type="box"/>')


def _region_pass_means(result, region=(slice(None), slice(None))) -> np.ndarray:
    return result.passes[:, region[0], region[1]].mean(axis=(1, 2))


def test_a_crop_window_renders_its_part_of_the_film(variant_llvm_rgb, tmp_path):
    """A film's crop window (offset 4, 2; 6 x 5 of 12 x 10): the uniform and the adaptive
    render are the crop's size and see, in expectation, what the full film sees there.
    Two-sample t-tests of the region's mean, per channel (8 passes against 8 passes, and 6
    adaptive seeds against the full film's passes), Šidák over the 6 tests."""
    from phonglab.engine import adaptive, scenes
    from phonglab.engine.render import render_scene

    text = CONTENT.format(integrator=PATH, fmt="rgb").replace(
        '<string name="pixel_format" value="rgb"/>', '<string name="pixel_format" value="rgb"/>'
        + CROP)
    crop = scenes.load_scene(_write(tmp_path, "crop.xml", text))
    full_box = scenes.load_scene(_write(tmp_path, "box.xml", text.replace(CROP, '<rfilter '
                                                                          'type="box"/>')))
    region = (slice(2, 7), slice(4, 10))
    a = _region_pass_means(render_scene(full_box, 256, seed=1, passes=8, keep_passes=True),
                           region)
    b_result = render_scene(crop, 256, seed=2, passes=8, keep_passes=True)
    assert b_result.image.shape == (5, 6, 3)
    b = _region_pass_means(b_result)
    c = np.array([adaptive.render_adaptive(crop, 0.03, seed=s).image.mean(axis=(0, 1))
                  for s in range(6)])
    z = stats.t_critical(5, stats.ALPHA, 6)      # the smaller sample: 6 seeds, 5 dof
    for x in (b, c):
        se = np.sqrt(a.var(axis=0, ddof=1) / len(a) + x.var(axis=0, ddof=1) / len(x))
        t = np.abs(a.mean(axis=0) - x.mean(axis=0)) / se
        assert np.all(t <= z), (a.mean(axis=0), x.mean(axis=0), t)
