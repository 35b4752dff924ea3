"""Hardened plugin parameters: refused updates change nothing, float32 limits, large bitmaps.

* A refused ``params.update()`` restores the last accepted values, so the next render is
  bit-identical to the one before it (same seed), and a later good update still works.
* Every numeric parameter of lambert, phong and whitted is finite in float32, not denormal
  and in range, at load and on update; the error is one sentence naming the parameter.
* A bitmap's reflectance check reads its texel data, whatever its size.
"""

from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

from phonglab.plugins._common import MaterialError

NAN, INF = math.nan, math.inf


@pytest.fixture(autouse=True)
def _rgb(variant_llvm_rgb):
    return variant_llvm_rgb


@pytest.fixture
def one_thread():
    """One Dr.Jit thread: after any ``params.update()`` (a successful one that changes
    nothing too) the LLVM backend may sum a pixel's samples in another order, 1 ulp
    apart; the comparison of images before and after must see only the material."""
    n = dr.thread_count()
    dr.set_thread_count(1)
    yield
    dr.set_thread_count(n)


def material_message(exc: BaseException) -> str | None:
    """The MaterialError sentence in ``exc``: the error itself (``params.update()``), the
    last line of Mitsuba's loader error (``mi.load_dict``), or the cause of ``mi.render``'s
    error (an exception inside a Dr.Jit custom operation); None when there is none."""
    if isinstance(exc, MaterialError):
        return str(exc)
    if isinstance(exc.__cause__, MaterialError):
        return str(exc.__cause__)
    text = str(exc)
    marker = "MaterialError: "
    return text[text.rindex(marker) + len(marker):] if marker in text else None


def tiny_scene(bsdf: dict | None = None, integrator: dict | None = None, res: int = 16,
               spp: int = 4) -> dict:
    """A sphere (BSDF id 'mat') under a point light, seen by a res x res camera."""
    return {"type": "scene",
            "integrator": integrator or {"type": "path", "max_depth": 3},
            "sphere": {"type": "sphere", "bsdf": {"id": "mat", **(bsdf or {"type": "phong"})}},
            "light": {"type": "point", "position": [1.0, 2.0, 3.0], "intensity": 4.0},
            "camera": {"type": "perspective", "fov": 45.0,
                       "to_world": mi.ScalarTransform4f().look_at([0, 0, 4], [0, 0, 0], [0, 1, 0]),
                       "film": {"type": "hdrfilm", "width": res, "height": res,
                                "pixel_format": "rgb"},
                       "sampler": {"type": "independent", "sample_count": spp}}}


def render(scene, seed: int = 7) -> np.ndarray:
    return np.array(mi.render(scene, seed=seed), dtype=np.float32)


def bitmap(data: np.ndarray) -> dict:
    return {"type": "bitmap", "bitmap": mi.Bitmap(np.ascontiguousarray(data, np.float32)),
            "raw": True}


WHITTED = {"type": "whitted", "max_depth": 2, "ambient": 0.1, "attenuation_linear": 0.2}

# (bsdf, integrator, parameter key, refused value, the parameter the error must name)
REFUSED = [
    ({"type": "phong"}, None, "exponent", -5.0, "exponent"),
    ({"type": "phong"}, None, "exponent", NAN, "exponent"),
    ({"type": "phong"}, None, "exponent", INF, "exponent"),
    ({"type": "phong"}, None, "exponent", 1e-45, "exponent"),
    ({"type": "phong"}, None, "diffuse_reflectance.value", 1.5, "diffuse_reflectance"),
    ({"type": "phong"}, None, "diffuse_reflectance.value", 1.0, "specular_reflectance"),  # 1.2
    ({"type": "phong", "diffuse_reflectance": {"type": "rgb", "value": [0.5, 0.4, 0.3]}}, None,
     "diffuse_reflectance.value", [0.5, 1.0, 0.3], "specular_reflectance"),
    ({"type": "lambert"}, None, "reflectance.value", 3.0, "reflectance"),
    ({"type": "lambert"}, None, "reflectance.value", NAN, "reflectance"),
    ({"type": "phong", "diffuse_reflectance": bitmap(np.full((4, 4, 3), 0.4))}, None,
     "diffuse_reflectance.data", "texel", "diffuse_reflectance"),
    ({"type": "phong"}, WHITTED, "attenuation_constant", NAN, "attenuation_constant"),
    ({"type": "phong"}, WHITTED, "attenuation_constant", 1e-45, "attenuation_constant"),
    ({"type": "phong"}, WHITTED, "attenuation_linear", INF, "attenuation_linear"),
    ({"type": "phong"}, WHITTED, "attenuation_quadratic", -1.0, "attenuation_quadratic"),
    ({"type": "phong"}, WHITTED, "ambient.value", -0.5, "ambient"),
    ({"type": "phong"}, WHITTED, "ambient.value", INF, "ambient"),
]


def _full_key(params, key: str) -> str:
    (full,) = [k for k in params.keys() if k.endswith("." + key)]
    return full


def _bad_value(params, key, value):
    if value == "texel":     # one texel of the bitmap above 1
        data = np.array(params[key])
        data[2, 1, 0] = 1.5
        return mi.TensorXf(data)
    return value


@pytest.mark.parametrize("bsdf, integrator, key, value, name", REFUSED,
                         ids=[f"{r[2]}={r[3]}" + ("-whitted" if r[1] else "") for r in REFUSED])
def test_refused_update_leaves_the_render_unchanged(one_thread, bsdf, integrator, key, value, name):
    scene = mi.load_dict(tiny_scene(bsdf, integrator))
    params = mi.traverse(scene)
    key = _full_key(params, key)
    before_values = {k: np.array(params[k]).copy() for k in params.keys()}
    before = render(scene)
    params[key] = _bad_value(params, key, value)
    with pytest.raises(MaterialError) as info:
        params.update()
    message = str(info.value)
    assert name in message and "\n" not in message, message
    for k, v in before_values.items():     # every traversed value is back, bit for bit
        np.testing.assert_array_equal(np.array(params[k]), v, err_msg=k)
    after = render(scene)
    assert np.array_equal(after, before), "a refused update changed the image"


@pytest.mark.parametrize("plugin, name, key, bad, good", [
    ("phong", "exponent", "exponent", -5.0, 5.0),
    ("phong", "diffuse_reflectance", "diffuse_reflectance.value", 1.5, 0.1),
    ("lambert", "reflectance", "reflectance.value", 3.0, 0.9),
])
def test_good_update_after_a_refused_one_takes_effect(plugin, name, key, bad, good):
    scene = mi.load_dict(tiny_scene({"type": plugin}))
    params = mi.traverse(scene)
    key = _full_key(params, key)
    before = render(scene)
    params[key] = bad
    with pytest.raises(MaterialError):
        params.update()
    params[key] = good
    params.update()
    assert float(np.array(params[key]).ravel()[0]) == pytest.approx(good)
    changed = render(scene)
    assert np.all(np.isfinite(changed)) and not np.array_equal(changed, before)
    # ... and it is what a scene loaded with that value renders.
    fresh = mi.load_dict(tiny_scene({"type": plugin, name: good}))
    np.testing.assert_allclose(changed, render(fresh), rtol=1e-5, atol=1e-6)


def test_refused_bitmap_update_restores_the_texels(one_thread):
    data = np.full((6, 5, 3), 0.3, np.float32)
    scene = mi.load_dict(tiny_scene({"type": "lambert", "reflectance": bitmap(data)}))
    params = mi.traverse(scene)
    key = _full_key(params, "reflectance.data")
    before = render(scene)
    bad = data.copy()
    bad[5, 4] = [0.3, 0.3, NAN]
    params[key] = mi.TensorXf(bad)
    with pytest.raises(MaterialError, match="non-finite"):
        params.update()
    np.testing.assert_array_equal(np.array(params[key]), data)
    assert np.array_equal(render(scene), before)


# ----------------------------------------------------------------------------- load time

LOAD_REFUSED = [
    ({"type": "phong", "exponent": 1e-45}, "exponent", "denormal"),
    ({"type": "phong", "exponent": 1e39}, "exponent", "finite"),
    ({"type": "phong", "diffuse_reflectance": 1e-40}, "diffuse_reflectance", "denormal"),
    ({"type": "phong", "specular_reflectance": {"type": "rgb", "value": [0.1, NAN, 0.1]}},
     "specular_reflectance", "non-finite"),
    ({"type": "lambert", "reflectance": -1e-45}, "reflectance", "denormal"),
    ({"type": "lambert", "reflectance": INF}, "reflectance", "non-finite"),
    # Within phonglab's float32 slack but above 1: Mitsuba's colour texture raised its own
    # "Invalid RGB reflectance value [0, 0, 1.0001]" (found by test_fuzz_load_long).
    ({"type": "lambert", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 1.0001]}},
     "reflectance", "[0, 1]"),
    ({"type": "whitted", "attenuation_constant": NAN}, "attenuation_constant", "finite"),
    ({"type": "whitted", "attenuation_constant": 1e-45}, "attenuation_constant", "denormal"),
    ({"type": "whitted", "attenuation_linear": INF}, "attenuation_linear", "finite"),
    ({"type": "whitted", "attenuation_quadratic": 1e39}, "attenuation_quadratic", "finite"),
    ({"type": "whitted", "ambient": -0.5}, "ambient", "[0, 1e+30]"),
    ({"type": "whitted", "ambient": 1e31}, "ambient", "[0, 1e+30]"),
    ({"type": "whitted", "ambient": {"type": "rgb", "value": [0.1, -0.2, 0.1]}}, "ambient",
     "[0, 1e+30]"),
    ({"type": "whitted", "ambient": NAN}, "ambient", "non-finite"),
    ({"type": "whitted", "ambient": 1e-42}, "ambient", "denormal"),
    ({"type": "whitted", "ambient_reflectance_mat": 1.5}, "ambient_reflectance_mat", "[0, 1]"),
    ({"type": "whitted", "ambient_reflectance_mat": NAN}, "ambient_reflectance_mat",
     "non-finite"),
    ({"type": "whitted", "max_depth": 2.5}, "max_depth", "1..10"),
    ({"type": "whitted", "max_depth": NAN}, "max_depth", "1..10"),
]


@pytest.mark.parametrize("spec, name, needle", LOAD_REFUSED,
                         ids=[f"{s['type']}-{n}-{i}" for i, (s, n, _) in enumerate(LOAD_REFUSED)])
def test_load_refuses_non_finite_denormal_and_out_of_range_values(spec, name, needle):
    with pytest.raises(Exception) as info:
        mi.load_dict(spec)
    message = material_message(info.value)
    assert message is not None, f"no MaterialError in: {info.value}"
    assert f"'{name}'" in message and needle in message and "\n" not in message, message


@pytest.mark.parametrize("integrator", [
    {"type": "whitted", "max_depth": 2, "attenuation_constant": 1e-44},
    {"type": "whitted", "max_depth": 2, "attenuation_linear": INF},
    {"type": "whitted", "max_depth": 2, "ambient": -0.5},
], ids=["denormal-a", "inf-b", "negative-ambient"])
def test_whitted_never_renders_nan_inf_or_negative_pixels(integrator):
    """The reported cases: each is refused at load (rendered, it gives NaN, black or < 0)."""
    try:
        scene = mi.load_dict(tiny_scene({"type": "phong"}, integrator))
    except Exception as exc:
        assert material_message(exc) is not None, exc
        return
    image = render(scene)
    assert np.all(np.isfinite(image)) and np.all(image >= 0), "NaN, Inf or negative pixels"


def test_unknown_ambient_reflectance_id_names_the_known_ids():
    scene = mi.load_dict(tiny_scene({"type": "phong"},
                                    {"type": "whitted", "ambient_reflectance_nope": 0.3}))
    with pytest.raises(Exception) as info:
        mi.render(scene)
    message = material_message(info.value)
    assert message is not None, info.value
    assert "'ambient_reflectance_nope'" in message and "'mat'" in message, message


def test_boundary_values_still_load():
    mi.load_dict({"type": "phong", "exponent": float(np.finfo(np.float32).tiny)})
    mi.load_dict({"type": "phong", "exponent": 1e30, "diffuse_reflectance": 0.0})
    mi.load_dict({"type": "whitted", "attenuation_constant": 0.0, "attenuation_linear": 1e-30})
    mi.load_dict({"type": "whitted", "ambient": 1e30, "max_depth": 10})
    mi.load_dict({"type": "whitted", "max_depth": 3.0})
    mi.load_dict({"type": "lambert", "reflectance": 0.0})


# ----------------------------------------------------------------------------- large bitmaps

@pytest.mark.parametrize("shape", [(1100, 1100), (8, 2048), (2048, 8)])
def test_bitmap_of_any_size_is_checked_on_every_texel(shape):
    data = np.full((*shape, 3), 0.4, np.float32)
    data[shape[0] - 3, shape[1] // 3 + 1, 1] = 1.5
    with pytest.raises(Exception) as info:
        mi.load_dict({"type": "lambert", "reflectance": bitmap(data)})
    message = material_message(info.value)
    assert message is not None and "'reflectance'" in message and "1.5" in message, info.value


def test_large_bitmap_energy_is_checked_on_every_texel():
    kd = np.full((1100, 1100, 3), 0.5, np.float32)
    kd[1037, 1041, 2] = 0.85                       # + k_s 0.2 = 1.05 at one texel
    with pytest.raises(Exception) as info:
        mi.load_dict({"type": "phong", "diffuse_reflectance": bitmap(kd),
                      "specular_reflectance": 0.2})
    message = material_message(info.value)
    assert message is not None and "violates energy conservation" in message, info.value
    assert "1.05" in message, message
    kd[1037, 1041, 2] = 0.8
    mi.load_dict({"type": "phong", "diffuse_reflectance": bitmap(kd), "specular_reflectance": 0.2})


def test_bitmaps_of_different_sizes_are_summed_on_the_finer_grid():
    kd = np.full((1030, 1030, 3), 0.5, np.float32)
    ks = np.full((8, 8, 3), 0.2, np.float32)
    kd[1029, 1029, 0] = 0.9                        # the corner texel + k_s 0.2 = 1.1
    with pytest.raises(Exception) as info:
        mi.load_dict({"type": "phong", "diffuse_reflectance": bitmap(kd),
                      "specular_reflectance": bitmap(ks)})
    assert "violates energy conservation" in (material_message(info.value) or ""), info.value


# ----------------------------------------------------------------------------- 8-bit bitmaps

def png8(tmp_path, data: np.ndarray, name: str) -> str:
    """``data`` (bytes, HxWxC or HxW) written as an 8-bit PNG; its path."""
    fmt = mi.Bitmap.PixelFormat.Y if data.ndim == 2 or data.shape[-1] == 1 else \
        mi.Bitmap.PixelFormat.RGB
    path = tmp_path / name
    mi.Bitmap(np.ascontiguousarray(data, np.uint8), pixel_format=fmt).write(str(path))
    return str(path)


@pytest.mark.parametrize("raw", [False, True], ids=["srgb", "raw"])
@pytest.mark.parametrize("channels", [3, 1], ids=["rgb", "gray"])
def test_8bit_png_textures_load_and_render_as_mitsuba_decodes_them(tmp_path, one_thread, raw,
                                                                   channels):
    """An 8-bit PNG of bytes 123..232 (decoded 0.20..0.80 through sRGB, 0.48..0.91 raw) used
    to be refused: the range check read the stored bytes (Mitsuba keeps them as uint8 and
    decodes at lookup).  lambert with it renders what Mitsuba's diffuse renders."""
    data = np.random.default_rng(3).integers(123, 233, (6, 5, channels)).astype(np.uint8)
    tex = {"type": "bitmap", "filename": png8(tmp_path, data, "kd.png"), "raw": raw}
    lam = mi.load_dict(tiny_scene({"type": "lambert", "reflectance": tex}))
    ref = mi.load_dict(tiny_scene({"type": "diffuse", "reflectance": tex}))
    np.testing.assert_allclose(render(lam), render(ref), rtol=2e-5, atol=1e-6)
    mi.load_dict({"type": "phong", "diffuse_reflectance": tex, "specular_reflectance": 0.05})


def test_8bit_png_energy_is_checked_on_the_decoded_texels(tmp_path):
    """sRGB byte 219 decodes to 0.708 and byte 203 to 0.597: with k_s 0.35 the first
    texel sums to 1.058 > 1 (refused) while every stored byte / 255 + 0.35 would be > 1."""
    data = np.full((4, 4, 3), 203, np.uint8)
    data[1, 2, 0] = 219
    kd = {"type": "bitmap", "filename": png8(tmp_path, data, "kd.png")}
    with pytest.raises(Exception) as info:
        mi.load_dict({"type": "phong", "diffuse_reflectance": kd, "specular_reflectance": 0.35})
    message = material_message(info.value)
    assert message is not None and "violates energy conservation" in message, info.value
    assert "1.058" in message, message
    data[1, 2, 0] = 203
    kd = {"type": "bitmap", "filename": png8(tmp_path, data, "ok.png")}
    mi.load_dict({"type": "phong", "diffuse_reflectance": kd, "specular_reflectance": 0.35})


# ----------------------------------------------------------------------------- across objects

@pytest.mark.parametrize("bad_key, bad", [("exponent", -5.0), ("exponent", NAN),
                                          ("diffuse_reflectance.value", 1.5)])
def test_a_refused_update_restores_every_object_it_touched(one_thread, bad_key, bad):
    """One update that scales the light by 10 and sets an invalid phong parameter is refused
    whole: the light keeps its intensity (the next render is not 10x brighter)."""
    scene = mi.load_dict(tiny_scene({"type": "phong"}))
    params = mi.traverse(scene)
    light, key = _full_key(params, "intensity.value"), _full_key(params, bad_key)
    before_values = {k: np.array(params[k]).copy() for k in params.keys()}
    before = render(scene)
    params[light] = params[light] * 10.0
    params[key] = bad
    with pytest.raises(MaterialError):
        params.update()
    for k, v in before_values.items():
        np.testing.assert_array_equal(np.array(params[k]), v, err_msg=k)
    assert np.array_equal(render(scene), before), "the refused update changed the light"
    params.update({light: params[light] * 10.0})     # a good update afterwards works
    np.testing.assert_allclose(render(scene), 10.0 * before, rtol=1e-4, atol=1e-6)
