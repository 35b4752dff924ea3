"""Property-based fuzzing of the textures real scenes carry, on every texture parameter.

A bitmap is drawn in one of the storages scene files bring -- an 8-bit PNG decoded through
sRGB (Mitsuba's default) or ``raw``, a 16-bit PNG, float32 texels -- with 1 or 3 channels,
1 to 6 texels a side, and put on one texture parameter of lambert or phong.  The oracle is
Mitsuba's own decoding, independent of phonglab's range check: the ``bitmap`` texture alone,
evaluated at its texel centres.  The property:

* when every decoded value lies in [0, 1] (and, for phong, k_d + k_s <= 1 at every texel, to
  the plugins' float32 slack ``TOLERANCE``), the BSDF loads, and a tiny scene renders finite,
  non-negative pixels -- lambert's equal to Mitsuba's ``diffuse`` with the same texture;
* otherwise the load is refused with one ``MaterialError`` sentence naming a parameter.

An ordinary 8-bit PNG is accepted: the check reads its reflectances, not its stored bytes
(123..232) (tests/test_plugin_hardening.py pins that case); this searches the rest.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from phonglab.plugins._common import TOLERANCE
from test_plugin_hardening import material_message, render, tiny_scene

FAST = settings(max_examples=30, deadline=None, derandomize=True, database=None,
                suppress_health_check=[HealthCheck.too_slow,
                                       HealthCheck.function_scoped_fixture])

STORAGE = ["u8-srgb", "u8-raw", "u16", "f32"]


@st.composite
def bitmaps(draw):
    storage = draw(st.sampled_from(STORAGE))
    channels = draw(st.sampled_from([1, 3]))
    h, w = draw(st.integers(1, 6)), draw(st.integers(1, 6))
    if storage.startswith("u8"):
        hi = draw(st.sampled_from([255, 240, 200]))
        data = draw(st.lists(st.integers(0, hi), min_size=h * w * channels,
                             max_size=h * w * channels))
        return storage, np.array(data, np.uint8).reshape(h, w, channels)
    if storage == "u16":
        data = draw(st.lists(st.integers(0, 65535), min_size=h * w * channels,
                             max_size=h * w * channels))
        return storage, np.array(data, np.uint16).reshape(h, w, channels)
    data = draw(st.lists(st.floats(0.0, 1.25, width=32), min_size=h * w * channels,
                         max_size=h * w * channels))
    return storage, np.array(data, np.float32).reshape(h, w, channels)


def texture(tmp_path, storage: str, data: np.ndarray, name: str) -> dict:
    """The ``bitmap`` texture dict of ``data`` in ``storage`` (PNG files for integer data)."""
    if storage == "f32":
        return {"type": "bitmap", "bitmap": mi.Bitmap(data), "raw": True}
    fmt = mi.Bitmap.PixelFormat.Y if data.shape[-1] == 1 else mi.Bitmap.PixelFormat.RGB
    path = tmp_path / f"{name}.png"
    mi.Bitmap(np.ascontiguousarray(data), pixel_format=fmt).write(str(path))
    return {"type": "bitmap", "filename": str(path), "raw": storage == "u8-raw"}


def decoded(tex: dict) -> np.ndarray:
    """Mitsuba's values of ``tex`` at its texel centres, (texels, channels)."""
    t = mi.load_dict(tex)
    data = np.asarray(mi.traverse(t)["data"])
    h, w = data.shape[:2]
    u, v = np.meshgrid((np.arange(w) + 0.5) / w, (np.arange(h) + 0.5) / h, indexing="xy")
    si = dr.zeros(mi.SurfaceInteraction3f, h * w)
    si.uv = mi.Point2f(u.ravel().astype(np.float32), v.ravel().astype(np.float32))
    return np.atleast_2d(np.array(t.eval(si), dtype=np.float64)).T.reshape(h * w, -1)


PARAMETERS = [("lambert", "reflectance"), ("phong", "diffuse_reflectance"),
              ("phong", "specular_reflectance")]


@pytest.mark.parametrize("plugin, name", PARAMETERS, ids=[f"{p}.{n}" for p, n in PARAMETERS])
@FAST
@given(bitmap=bitmaps(), other=st.sampled_from([0.0, 0.2, 0.5]))
def test_bitmap_textures_load_as_mitsuba_decodes_them(variant_llvm_rgb, tmp_path, plugin, name,
                                                      bitmap, other):
    storage, data = bitmap
    tex = texture(tmp_path, storage, data, "tex")
    values = decoded(tex)
    spec = {"type": plugin, name: tex}
    total = values
    if plugin == "phong":        # the other lobe as a constant
        partner = ("specular_reflectance" if name == "diffuse_reflectance"
                   else "diffuse_reflectance")
        spec[partner] = other
        total = values + other
    valid = values.min() >= 0 and values.max() <= 1 + TOLERANCE and total.max() <= 1 + TOLERANCE
    try:
        scene = mi.load_dict(tiny_scene(spec, res=8, spp=1))
    except Exception as exc:
        message = material_message(exc)
        assert message is not None and "\n" not in message, exc
        assert not valid, f"refused a valid {storage} texture ({values.min()}..{values.max()}, " \
                          f"sum {total.max()}): {message}"
        return
    assert valid, f"accepted a {storage} texture beyond [0, 1]: {values.min()}..{total.max()}"
    image = render(scene)
    assert np.all(np.isfinite(image)) and np.all(image >= 0)
    if plugin == "lambert":
        ref = render(mi.load_dict(tiny_scene({"type": "diffuse", "reflectance": tex}, res=8,
                                             spp=1)))
        np.testing.assert_allclose(image, ref, rtol=1e-4, atol=1e-6)
