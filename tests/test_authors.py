"""Author-facing entry points (#38): --timeout / timeout=, --plugin for check and fit, the
types a Python plugin returns checked before Dr.Jit sees them."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import pytest

HERE = Path(__file__).parent
AUTHORS = HERE / "authors"
SRC = HERE.parent / "src"


def cli(*args, timeout=300):
    import os
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    return subprocess.run([sys.executable, "-m", "phonglab.cli", *map(str, args)],
                          capture_output=True, text=True, timeout=timeout, env=env)


def test_timeout_turns_a_hanging_eval_into_a_failing_row():
    """eval loops forever: the topics calling it fail by the timeout, the others pass."""
    from phonglab.testing import assert_bsdf_valid

    t0 = time.perf_counter()
    with pytest.raises(AssertionError) as info:
        assert_bsdf_valid("defect_hang_eval", plugins=[AUTHORS / "hang_eval.py"], sweep=False,
                          quick=True, topics=["finite", "chi2"], timeout=1)
    text = str(info.value)
    assert "did not finish within 1 s" in text and "finite" in text
    assert "chi2" not in text              # sample and pdf only: it still passes (component
    #                                        now evaluates eval below the surface too)
    assert time.perf_counter() - t0 < 60


def test_timeout_is_checked_before_work():
    r = cli("validate", "diffuse", "--timeout", "0")
    assert r.returncode == 2 and "--timeout must be" in r.stderr and "Traceback" not in r.stderr


def test_check_takes_the_authors_lambert_by_plugin():
    before = cli("check", "--lambert", "my_lambert", "--only", "sanity", "--no-progress")
    assert before.returncode == 2 and "--plugin FILE.py" in before.stderr
    r = cli("check", "--lambert", "my_lambert", "--plugin", AUTHORS / "my_lambert.py",
            "--only", "sanity", "--no-progress", "--spp", "16")     # 65536 χ² samples: ~1 s
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    assert "my_lambert: χ² sampling" in r.stdout


def test_fit_takes_the_authors_bsdf_by_plugin():
    r = cli("fit", "my_lambert", "--set", "reflectance=0.3", "--model", "lambert",
            "--plugin", AUTHORS / "my_lambert.py")
    assert r.returncode == 0, r.stderr[-2000:]
    assert "fitted  k_d = 0.3" in r.stdout


@pytest.mark.parametrize("command", [["fit", "x"], ["check", "--only", "sanity", "--spp", "16"]])
def test_plugin_files_checked_before_work(command, tmp_path):
    r = cli(*command, "--plugin", tmp_path / "missing.py")
    assert r.returncode == 2 and "does not exist" in r.stderr and "Traceback" not in r.stderr
    r = cli(*command, "--plugin", tmp_path)
    assert r.returncode == 2 and "is a folder" in r.stderr and "Traceback" not in r.stderr
    taken = tmp_path / "taken.py"
    taken.write_text((AUTHORS / "my_lambert.py").read_text().replace('"my_lambert"', '"diffuse"'))
    r = cli(*command, "--plugin", taken)
    assert r.returncode == 2 and "a name Mitsuba already has" in r.stderr, r.stderr


def test_integrator_returning_the_wrong_type_is_one_sentence_not_an_abort():
    """Before: exit 134 inside Dr.Jit ("Referenced an unknown variable"), no report."""
    r = cli("validate", "defect_wrong_return", "--plugin", AUTHORS / "wrong_return_integrator.py",
            "--quick", "--no-sweep")
    assert r.returncode == 2, (r.returncode, r.stderr[-1500:])
    assert "sample() of the integrator 'defect_wrong_return' returned Color3f" in r.stderr
    assert "(L: the radiance" in r.stderr and "valid: mi.Bool; aovs" in r.stderr
    assert "Traceback" not in r.stderr


@pytest.mark.parametrize("method, old, new, said", [
    ("eval_pdf", "return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)",
     "return self.eval(ctx, si, wo, active)", "eval_pdf() of the BSDF 'bad_return' returned Color3f"),
    ("sample", "return bs, dr.select(bs.pdf > 0, value, 0.0)", "return bs",
     "sample() of the BSDF 'bad_return' returned BSDFSample3f"),
    ("pdf", "return dr.select(self._ok(si, wo, ctx), mi.warp.square_to_cosine_hemisphere_pdf(wo), 0.0)",
     "return mi.Vector3f(1, 2, 3)", "pdf() of the BSDF 'bad_return' returned Vector3f"),
])
def test_bsdf_returning_the_wrong_type_names_the_method(method, old, new, said, tmp_path):
    text = (AUTHORS / "my_lambert.py").read_text()
    assert old in text
    bad = tmp_path / "bad.py"
    bad.write_text(text.replace(old, new).replace('"my_lambert"', '"bad_return"'))
    r = cli("validate", "bad_return", "--plugin", bad, "--quick", "--no-sweep", "--only", "finite")
    assert r.returncode == 2 and said in r.stderr, r.stderr[-1500:]
    assert "Traceback" not in r.stderr


def test_gpu_check_skips_cleanly_without_cuda():
    """scripts/gpu_check.py: where cuda_ad_rgb does not work, a SKIPPED line and exit 0 (77
    with --require-gpu); on a GPU machine this test is skipped (run the script itself)."""
    script = HERE.parent / "scripts" / "gpu_check.py"
    spec = __import__("importlib.util").util.spec_from_file_location("gpu_check", script)
    mod = __import__("importlib.util").util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    if mod.variant_works("cuda_ad_rgb") is None:
        pytest.skip("cuda_ad_rgb works here: run scripts/gpu_check.py")
    r = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0 and r.stdout.startswith("SKIPPED: cuda_ad_rgb"), r.stdout + r.stderr
    r = subprocess.run([sys.executable, str(script), "--require-gpu"], capture_output=True,
                       text=True, timeout=300)
    assert r.returncode == 77


def test_timeout_stops_an_integrator_looping_inside_a_render():
    """sample() loops forever inside mi.render: Dr.Jit's custom op re-raises the timeout as a
    RuntimeError, which must still read as the timeout."""
    t0 = time.perf_counter()
    r = cli("validate", "defect_hang_sample", "--plugin", AUTHORS / "hang_integrator.py",
            "--quick", "--no-sweep", "--timeout", "1", "--only", "finite", "--only", "cost",
            timeout=120)
    assert r.returncode == 1, r.stderr[-1500:]
    assert r.stdout.count("did not finish within 1 s") == 2, r.stdout[-2000:]
    assert time.perf_counter() - t0 < 60


def test_phase_function_returning_the_wrong_type_names_the_method(tmp_path):
    """Before: every topic failed with "too many values to unpack (expected 2)"."""
    text = (HERE / "defects_phase" / "hg_control.py").read_text()
    assert "return mi.Spectrum(p), p" in text
    bad = tmp_path / "badphase.py"
    bad.write_text(text.replace("return mi.Spectrum(p), p", "return mi.Spectrum(p)")
                   .replace('mi.register_phase("defect_hg_control"',
                            'mi.register_phase("bad_phase_return"'))
    assert "bad_phase_return" in bad.read_text()
    r = cli("validate", "bad_phase_return", "--plugin", bad, "--quick", "--no-sweep")
    assert r.returncode == 2, r.stdout[-1500:] + r.stderr[-1500:]
    assert "eval_pdf() of the phase function 'bad_phase_return' returned Color3f" in r.stderr
