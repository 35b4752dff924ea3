"""phonglab.register(), the LLVM pinning and the variants the plugins promise to work in."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

import phonglab
from phonglab import runtime

PY = sys.executable


def run_py(code: str, env=None) -> subprocess.CompletedProcess:
    return subprocess.run([PY, "-c", code], capture_output=True, text=True, timeout=120,
                          env={**os.environ, **(env or {})})


def test_llvm_variant_is_usable():
    """Fails loudly (not a skip) on a machine where the default JIT variant cannot run."""
    choice = runtime.configure()
    assert choice.usable, f"LLVM backend unusable: {choice.reason}. Run `make setup` as root."
    assert choice.major not in runtime.BROKEN_MAJORS
    assert phonglab.register("llvm_ad_rgb") == "llvm_ad_rgb"
    assert dr.detail.llvm_version()[0] == choice.major


def test_import_sets_no_variant_and_register_sets_llvm():
    out = run_py("import mitsuba as mi, phonglab; print(mi.variant());"
                 "print(phonglab.register()); print(mi.variant())")
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["None", "llvm_ad_rgb", "llvm_ad_rgb"]


def test_register_keeps_an_active_variant_and_is_idempotent():
    code = ("import mitsuba as mi, phonglab; mi.set_variant('llvm_ad_mono');"
            "print(phonglab.register()); print(phonglab.register());"
            "print(mi.load_dict({'type': 'phong'}).class_name())")
    out = run_py(code)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split()[:2] == ["llvm_ad_mono", "llvm_ad_mono"]


def test_plugins_follow_later_set_variant_calls():
    code = ("import mitsuba as mi, phonglab; phonglab.register();"
            "mi.set_variant('scalar_rgb'); b = mi.load_dict({'type': 'lambert'});"
            "mi.set_variant('llvm_ad_spectral'); c = mi.load_dict({'type': 'phong'});"
            "mi.set_variant('llvm_ad_rgb'); d = mi.load_dict({'type': 'phong'});"
            "print(b.variant_name(), c.variant_name(), d.variant_name())")
    out = run_py(code)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["scalar_rgb", "llvm_ad_spectral", "llvm_ad_rgb"]


def test_library_major_parsing():
    assert runtime.library_major("/usr/lib/x86_64-linux-gnu/libLLVM-19.so") == 19
    assert runtime.library_major("libLLVM.so.19.1") == 19
    assert runtime.library_major("/usr/lib/llvm-18/lib/libLLVM.so") == 18
    assert runtime.library_major("libLLVM-15.so.1") == 15


def test_broken_llvm_in_environment_is_refused_and_falls_back_loudly(monkeypatch, tmp_path):
    fake = tmp_path / "libLLVM-15.so"
    fake.write_bytes(b"")
    monkeypatch.setenv(runtime.ENV, str(fake))
    choice = runtime.configure(force=True)
    try:
        assert not choice.usable and "15" in choice.reason and "libllvm19" in choice.reason
        with pytest.warns(runtime.SlowFallbackWarning, match="150x slower"):
            assert runtime.default_variant() == "scalar_rgb"
    finally:
        monkeypatch.undo()
        runtime.configure(force=True)


def test_scalar_fallback_end_to_end_without_llvm():
    """A process whose libLLVM is unusable still renders, in scalar_rgb, with a warning."""
    code = ("import warnings, mitsuba as mi, phonglab;"
            "warnings.simplefilter('always');"
            "v = phonglab.register(); print(v);"
            "mi.load_dict({'type': 'phong'})")
    out = run_py(code, env={runtime.ENV: "/nonexistent/libLLVM-19.so"})
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["scalar_rgb"]
    assert "150x slower" in out.stderr


@pytest.mark.parametrize("kind", ["lambert", "phong"])
def test_plugin_in_every_variant_from_dict_xml_and_twosided(any_variant, kind):
    params = {"lambert": '<rgb name="reflectance" value="0.2, 0.5, 0.8"/>',
              "phong": '<rgb name="diffuse_reflectance" value="0.5, 0.3, 0.2"/>'
                       '<float name="specular_reflectance" value="0.3"/>'
                       '<float name="exponent" value="20"/>'}[kind]
    from_xml = mi.load_string(f'<bsdf version="3.0.0" type="{kind}">{params}</bsdf>')
    from_dict = mi.load_dict({"type": kind})
    two = mi.load_string(f'<bsdf version="3.0.0" type="twosided"><bsdf type="{kind}">{params}'
                         f'</bsdf></bsdf>')
    si = dr.zeros(mi.SurfaceInteraction3f)
    if mi.is_spectral:
        si.wavelengths = mi.Spectrum(450.0, 500.0, 550.0, 600.0)
    ctx = mi.BSDFContext()
    for bsdf, wi_z in ((from_xml, 0.8), (from_dict, 0.8), (two, -0.8)):
        si.wi = dr.normalize(mi.Vector3f(0.3, 0.1, wi_z))
        bs, weight = bsdf.sample(ctx, si, 0.3, mi.Point2f(0.4, 0.6))
        value = bsdf.eval(ctx, si, bs.wo)
        w = np.array(weight, dtype=float).ravel()
        assert np.all(np.isfinite(w)) and np.all(w > 0), (any_variant, kind, w)
        assert np.all(np.array(value, dtype=float) > 0)
        # Back-side incidence on the one-sided BSDF reflects nothing.
    si.wi = mi.Vector3f(0.0, 0.0, -1.0)
    bs, weight = from_dict.sample(ctx, si, 0.3, mi.Point2f(0.4, 0.6))
    assert np.all(np.array(weight, dtype=float) == 0)


def test_scene_renders_in_every_variant(any_variant, scenes_dir):
    from phonglab.engine.render import render_scene
    from phonglab.engine.scenes import load_scene

    spp = 1 if any_variant.startswith("scalar") else 4
    scene = load_scene(scenes_dir / "cornell_phong.xml", any_variant, res=16 if spp == 1 else 32,
                       spp=spp)
    result = render_scene(scene, spp=spp)
    assert np.all(np.isfinite(result.image)) and result.image.mean() > 0.01


@pytest.mark.parametrize("variant", ["llvm_ad_mono_polarized", "llvm_ad_spectral_polarized"])
def test_polarized_variants_render_like_unpolarized(variant, scenes_dir):
    """The plugins return an ideal depolarizer (as diffuse.cpp does), so a polarized variant
    renders the scene (no polarizing element in it) exactly as the unpolarized one, seed for seed."""
    from phonglab.engine.render import render_scene
    from phonglab.engine.scenes import load_scene

    images = []
    for v in (variant, variant.replace("_polarized", "")):
        scene = load_scene(scenes_dir / "cornell_phong.xml", v, res=16, spp=16)
        images.append(render_scene(scene, spp=16, seed=3).image)
    assert images[0].mean() > 0.05
    np.testing.assert_allclose(images[0], images[1], rtol=1e-5, atol=1e-6)


def test_cuda_without_a_device_falls_back_to_llvm_not_scalar():
    """A cuda_* variant on a machine without a CUDA device runs on LLVM (not ~150x slower scalar)."""
    if dr.has_backend(dr.JitBackend.CUDA):
        pytest.skip("this machine has a CUDA device: cuda_ad_rgb starts, no fallback to test")
    with pytest.warns(runtime.BackendFallbackWarning, match="cuda_ad_rgb is unusable.*llvm_ad_rgb"):
        assert runtime.set_variant("cuda_ad_rgb") == "llvm_ad_rgb"
    with pytest.warns(runtime.BackendFallbackWarning):
        assert phonglab.register("cuda_ad_mono") == "llvm_ad_mono"
    phonglab.register("llvm_ad_rgb")


@pytest.mark.skipif(not hasattr(os, "sched_setaffinity"), reason="needs an affinity mask")
def test_one_core_gets_two_kernel_threads_and_reads_and_writes_exr(tmp_path):
    """On one core (an affinity mask of one CPU, as a one-CPU container gives) Dr.Jit defaults
    to one thread, at which Mitsuba 3.9.1 waits forever on an OpenEXR file
    (tests/repro/exr_one_thread_hang.py).  phonglab.register gives it a second thread, born
    in the background class (SCHED_IDLE), so a render's EXR output or an EXR texture returns;
    before, this child hung until its time limit."""
    code = (
        "import json, os, numpy as np\n"
        "import phonglab, drjit as dr, mitsuba as mi\n"
        "phonglab.register('llvm_ad_rgb')\n"
        "mi.Bitmap(np.full((8, 8, 3), 0.4, dtype=np.float32)).write('t.exr')\n"
        "assert list(mi.Bitmap('t.exr').size()) == [8, 8]\n"
        "print(json.dumps([dr.thread_count(), [os.sched_getscheduler(int(t)) for t in\n"
        "                  os.listdir('/proc/self/task')]]))\n")
    done = subprocess.run([PY, "-c", code], capture_output=True, text=True, timeout=60,
                          cwd=tmp_path, preexec_fn=lambda: os.sched_setaffinity(0, {0}))
    assert done.returncode == 0, done.stderr[-2000:]
    threads, classes = json.loads(done.stdout)
    assert threads == runtime.MIN_KERNEL_THREADS
    assert os.SCHED_IDLE in classes                 # the added kernel thread
