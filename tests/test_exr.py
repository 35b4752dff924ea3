"""EXR files: round trip with provenance, atomic writes, clear read errors; and the numbers of
``phonglab.engine.compare`` on synthetic images whose answers are known in closed form.

Cheapest first: pure numpy/OpenEXR checks, then one tiny render (provenance), then a
calibration test of the compare's standard error (statistical: α = 0.01, Šidák over its
two cases, fixed seed).
"""

from __future__ import annotations

import math
import os

import numpy as np
import pytest
from scipy import stats

from phonglab.stats import ALPHA, sidak
from phonglab.engine import compare, exr, scenes
from phonglab.errors import CompareError, ExrError
from phonglab.engine.metrics import REL_EPS

RNG = np.random.default_rng(20261121)


def _image(shape):
    return RNG.random(shape).astype(np.float32) * 4.0 - 1.0   # negative values survive too


# ------------------------------------------------------------------------------ round trip
@pytest.mark.parametrize("shape", [(7, 5), (7, 5, 1), (7, 5, 3), (7, 5, 4)],
                         ids=["Y", "Y1", "RGB", "RGBA"])
def test_round_trip_is_bit_exact_with_metadata(tmp_path, shape):
    img = _image(shape)
    meta = {"scene": "scenes_xml/x.xml", "scene_sha256": "ab" * 32, "variant": "llvm_ad_rgb",
            "spp": 64, "seed": 3, "integrator": "PathIntegrator", "max_depth": 8,
            "render_seconds": 1.25, "phonglab_version": "0.1.0", "mitsuba_version": "3.9.1",
            "passes": None, "list": [1, 2.5, "x"]}
    path = exr.write(tmp_path / "a.exr", img, meta)
    back, meta_back = exr.read(path)
    expected = img[..., 0] if shape == (7, 5, 1) else img
    assert back.dtype == np.float32 and back.shape == expected.shape
    assert np.array_equal(back, expected)
    assert meta_back == meta                      # types survive: int, float, None, list


def test_non_json_metadata_is_stored_as_text(tmp_path):
    path = exr.write(tmp_path / "a.exr", _image((2, 2, 3)), {"scene": tmp_path / "s.xml"})
    assert exr.read(path)[1]["scene"] == str(tmp_path / "s.xml")


def test_written_file_has_the_usual_permissions(tmp_path):
    path = exr.write(tmp_path / "a.exr", _image((2, 2)))
    mask = os.umask(0)
    os.umask(mask)
    assert os.stat(path).st_mode & 0o777 == 0o666 & ~mask


@pytest.mark.parametrize("shape", [(4,), (2, 2, 2), (2, 2, 5), (1, 2, 2, 3)])
def test_unwritable_shapes_are_refused(tmp_path, shape):
    with pytest.raises(ExrError, match="pass an array of shape"):
        exr.write(tmp_path / "a.exr", np.zeros(shape))
    assert not list(tmp_path.iterdir())


# ------------------------------------------------------------------------------ atomic writes
class _DiesMidway:
    """Stands in for OpenEXR.File: writes half a file at the path it is given, then fails."""

    def __init__(self, header, channels, error=RuntimeError("disk full")):
        self.error = error

    def write(self, path):
        with open(path, "wb") as f:
            f.write(exr.MAGIC + b"\0" * 100)     # a truncated EXR
        raise self.error


@pytest.mark.parametrize("error", [RuntimeError("disk full"), KeyboardInterrupt()],
                         ids=["error", "ctrl-c"])
def test_interrupted_write_leaves_the_old_file_intact(tmp_path, monkeypatch, error):
    old = _image((6, 4, 3))
    path = exr.write(tmp_path / "render.exr", old, {"spp": 1})
    before = path.read_bytes()
    monkeypatch.setattr(exr.OpenEXR, "File", lambda h, c: _DiesMidway(h, c, error))
    with pytest.raises(type(error)):
        exr.write(path, _image((6, 4, 3)), {"spp": 2})
    monkeypatch.undo()
    assert path.read_bytes() == before
    img, meta = exr.read(path)
    assert np.array_equal(img, old) and meta == {"spp": 1}
    assert [p.name for p in tmp_path.iterdir()] == ["render.exr"], "temporary file left behind"


def test_interrupted_first_write_leaves_no_file(tmp_path, monkeypatch):
    monkeypatch.setattr(exr.OpenEXR, "File", _DiesMidway)
    with pytest.raises(RuntimeError):
        exr.write(tmp_path / "new.exr", _image((2, 2)))
    assert not list(tmp_path.iterdir())


# ------------------------------------------------------------------------------ read errors
def test_missing_file(tmp_path):
    with pytest.raises(FileNotFoundError, match="no such EXR file.*check the path"):
        exr.read(tmp_path / "nope.exr")


def test_png_is_not_an_exr(tmp_path):
    png = tmp_path / "a.png"
    png.write_bytes(b"\x89PNG\r\n\x1a\n" + b"\0" * 64)
    with pytest.raises(ExrError, match="not an OpenEXR file.*not its .png preview"):
        exr.read(png)


def test_truncated_exr(tmp_path):
    path = exr.write(tmp_path / "a.exr", _image((32, 32, 3)))
    cut = tmp_path / "cut.exr"
    cut.write_bytes(path.read_bytes()[:120])
    with pytest.raises(ExrError, match="damaged or truncated.*render it again"):
        exr.read(cut)


# ------------------------------------------------------------------------------ provenance of renders
def test_render_file_writes_its_provenance(tmp_path, variant_llvm_rgb):
    import mitsuba as mi

    from phonglab import __version__

    from phonglab.engine import render

    scene = scenes.scene_path("nb_emitter_distance")
    out = tmp_path / "e.exr"
    result = render.render_file(scene, out, spp=16, progress=False)
    img, meta = exr.read(out)
    assert np.array_equal(img, result.image)
    assert meta["scene"] == str(scene)
    assert meta["scene_sha256"] == scenes.file_hash(scene)
    assert (meta["variant"], meta["spp"], meta["seed"]) == (variant_llvm_rgb, 16, 0)
    assert meta["integrator"] == "PathIntegrator" and meta["max_depth"] == 1
    assert meta["render_seconds"] > 0
    assert (meta["phonglab_version"], meta["mitsuba_version"]) == (__version__, mi.__version__)
    # 16 spp render in passes, so the standard-error image sits beside it, same shape.
    se, se_meta = exr.read(exr.stderr_path(out))
    assert se.shape == img.shape and se_meta == meta
    # The emitter's interior is exactly its radiance, L = 1 (header of nb_emitter_distance.xml).
    assert np.all(img[28:36, 28:36] == 1.0)


# ------------------------------------------------------------------------------ compare: exact numbers
def test_constant_offset():
    b = RNG.random((16, 8, 3)) + 0.5
    c = 0.25
    r = compare.compare_arrays(b + c, b)
    assert r.rmse == pytest.approx(c, rel=1e-12)
    assert r.max_abs_diff == pytest.approx(c, rel=1e-12)
    assert r.mean_diff == pytest.approx(c, rel=1e-12)
    assert r.rel_mse == pytest.approx(np.mean(c * c / (b * b + REL_EPS)), rel=1e-12)
    assert r.channel_mean_diff == pytest.approx([c] * 3, rel=1e-12)
    # Every pixel differs by exactly c: no spread, so no standard error and no test.
    assert r.mean_diff_stderr == pytest.approx(0.0, abs=1e-15)


def test_checkerboard_difference():
    """d = ±δ on alternate pixels (n even): RMSE δ, mean 0, sd(ddof=1) = δ √(n/(n−1)),
    so SE = δ / √(n − 1)."""
    h, w, delta = 10, 12, 0.3
    n = h * w
    sign = np.where((np.arange(h)[:, None] + np.arange(w)[None, :]) % 2 == 0, 1.0, -1.0)
    b = RNG.random((h, w, 3))
    a = b + delta * sign[..., None]
    r = compare.compare_arrays(a, b)
    assert r.rmse == pytest.approx(delta, rel=1e-12)
    assert r.mean_diff == pytest.approx(0.0, abs=1e-15)
    assert r.stderr_source == "pixel differences"
    assert r.mean_diff_stderr == pytest.approx(delta / math.sqrt(n - 1), rel=1e-12)
    assert r.z == pytest.approx(0.0, abs=1e-12) and r.p_value == pytest.approx(1.0)


def test_stderr_from_files():
    """Constant per-pixel errors s, t: SE(d̄) = √(n (s² + t²)) / n."""
    h, w, s, t = 8, 8, 0.02, 0.05
    b = RNG.random((h, w, 3))
    a = b + 0.01
    r = compare.compare_arrays(a, b, np.full_like(a, s), np.full_like(b, t))
    assert r.stderr_source == "stderr files"
    assert r.mean_diff_stderr == pytest.approx(math.sqrt((s * s + t * t) / (h * w)), rel=1e-12)
    assert r.z == pytest.approx(0.01 / r.mean_diff_stderr, rel=1e-9)
    assert r.p_value == pytest.approx(2 * stats.norm.sf(r.z), rel=1e-9)


def test_mismatched_shapes_are_refused():
    with pytest.raises(CompareError, match=r"A is 4 x 5 x 3 but B is 4 x 6 x 3.*same resolution"):
        compare.compare_arrays(np.zeros((4, 5, 3)), np.zeros((4, 6, 3)))
    with pytest.raises(CompareError, match="standard-error image of A is 4 x 5 x 1"):
        compare.compare_arrays(np.zeros((4, 5, 3)), np.zeros((4, 5, 3)), np.zeros((4, 5)),
                               np.zeros((4, 5, 3)))


def test_non_finite_values_are_refused():
    a = np.zeros((2, 2, 3))
    a[0, 0, 1] = np.nan
    with pytest.raises(CompareError, match="A has 1 NaN or infinite"):
        compare.compare_arrays(a, np.zeros((2, 2, 3)))


def test_compare_files_finds_the_stderr_files(tmp_path):
    b = RNG.random((8, 8, 3)).astype(np.float32)
    a = (b + 0.1).astype(np.float32)
    exr.write(tmp_path / "a.exr", a, {"spp": 4})
    exr.write(tmp_path / "b.exr", b, {"spp": 8})
    r, *_ = compare.compare_files(tmp_path / "a.exr", tmp_path / "b.exr")
    assert r.stderr_source == "pixel differences"
    exr.write(tmp_path / "a.stderr.exr", np.full_like(a, 0.03))
    exr.write(tmp_path / "b.stderr.exr", np.full_like(b, 0.04))
    r, _, _, meta_a, meta_b = compare.compare_files(tmp_path / "a.exr", tmp_path / "b.exr")
    assert r.stderr_source == "stderr files"
    assert r.mean_diff_stderr == pytest.approx(0.05 / 8, rel=1e-6)    # √(0.03² + 0.04²) / √64
    assert (meta_a, meta_b) == ({"spp": 4}, {"spp": 8})
    with pytest.raises(CompareError, match="without --stderr-b"):
        compare.compare_files(tmp_path / "a.exr", tmp_path / "b.exr",
                              stderr_a=tmp_path / "a.stderr.exr")


def test_diff_png(tmp_path):
    b = np.zeros((20, 30, 3))
    a = b.copy()
    a[:, :15] += 1.0                          # left half brighter in A: red side of RdBu_r
    path = compare.write_diff_png(tmp_path / "d" / "diff.png", a, b)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert [p.name for p in path.parent.iterdir()] == ["diff.png"]


# ------------------------------------------------------------------------------ compare: calibration
@pytest.mark.parametrize("source", ["stderr files", "pixel differences"])
def test_mean_difference_test_is_calibrated(source):
    """Under H0 (A and B are independent noisy copies of one image) p < α should happen with
    probability α.  Over R fixed-seed repetitions the count of rejections is Binomial(R, α);
    the test fails if a two-sided binomial test rejects that at ALPHA (Šidák over 2 cases).
    The noise is the same in every channel of a pixel (perfectly correlated channels, the
    case the conservative stderr bound is exact for)."""
    rng = np.random.default_rng(7)
    reps, alpha_inner, (h, w) = 2000, 0.05, (12, 10)
    truth = rng.random((h, w, 1)) * np.array([1.0, 0.5, 0.2])
    sigma_a = 0.05 + 0.1 * rng.random((h, w, 1))
    sigma_b = 0.02 + 0.05 * rng.random((h, w, 1))
    rejections = 0
    for _ in range(reps):
        a = truth + sigma_a * rng.standard_normal((h, w, 1))
        b = truth + sigma_b * rng.standard_normal((h, w, 1))
        if source == "stderr files":
            r = compare.compare_arrays(a, b, np.broadcast_to(sigma_a, (h, w, 3)),
                                       np.broadcast_to(sigma_b, (h, w, 3)))
        else:
            r = compare.compare_arrays(a, b)
        assert r.stderr_source == source
        rejections += r.p_value < alpha_inner
    p = stats.binomtest(rejections, reps, alpha_inner).pvalue
    assert p > sidak(ALPHA, 2), (f"{source}: {rejections}/{reps} rejections at α = "
                                 f"{alpha_inner}, expected {alpha_inner * reps:.0f}")
