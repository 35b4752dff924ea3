"""Author-facing entry points: --timeout / timeout=, --plugin for check, fit and render, the
types a Python plugin returns checked before Dr.Jit sees them; and every message about an
author's plugin whole: which parameters `check` sets on it, an emitter named as such, a
parameter it never reads named whatever its value, its own errors in `fit` and `check`, a file
that switches the variant."""

from __future__ import annotations

import gc
import runpy
import subprocess
import sys
import time
from pathlib import Path

import mitsuba as mi
import pytest

from phonglab.cli import main as phonglab
from phonglab.engine import exr
from phonglab.settings import PluginError, load_plugin, mitsuba_reason

from helpers import fails_in_one_sentence
from test_fuzz_cli import TINY

HERE = Path(__file__).parent
AUTHORS = HERE / "authors"
SRC = HERE.parent / "src"


def cli(*args, timeout=300):
    """``phonglab ARGS`` in a process of its own (for what only a process shows: an abort, a
    signal's timeout inside a render)."""
    import os
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    return subprocess.run([sys.executable, "-m", "phonglab.cli", *map(str, args)],
                          capture_output=True, text=True, timeout=timeout, env=env)


def test_timeout_turns_a_hanging_eval_into_a_failing_row():
    """eval loops forever: the topics calling it fail by the timeout, the others pass, and
    no instance of the plugin outlives the run (Dr.Jit traces every live instance in each
    later symbolic call: a render of another scene in this process ran the hanging eval
    forever while a reference cycle through the timeout's traceback kept one alive)."""
    from phonglab.testing import assert_bsdf_valid

    t0 = time.perf_counter()
    with pytest.raises(AssertionError) as info:
        assert_bsdf_valid("defect_hang_eval", plugins=[AUTHORS / "hang_eval.py"], sweep=False,
                          quick=True, topics=["finite", "chi2"], timeout=1)
    text = str(info.value)
    assert "did not finish within 1 s" in text and "finite" in text
    assert "chi2" not in text              # sample and pdf only: it passes (component
    #                                        evaluates eval below the surface too)
    assert time.perf_counter() - t0 < 60
    assert not [o for o in gc.get_objects() if type(o).__name__ == "HangEval"]


def test_timeout_is_checked_before_work(capsys):
    fails_in_one_sentence(capsys, ["validate", "diffuse", "--timeout", "0"], "--timeout must be")


def test_check_takes_the_authors_lambert_by_plugin(tmp_path, capsys):
    # the author's file under a name no other test registers in this process
    mine = _as(tmp_path, "lambert_by_plugin")
    fails_in_one_sentence(capsys, ["check", "--lambert", "lambert_by_plugin", "--only", "sanity",
                                   "--no-progress"], "--plugin FILE.py")
    assert phonglab(["check", "--lambert", "lambert_by_plugin", "--plugin", str(mine),
                     "--only", "sanity", "--no-progress", "--spp", "16"]) == 0   # 65536 χ²: ~1 s
    assert "lambert_by_plugin: χ² sampling" in capsys.readouterr().out


def test_fit_takes_the_authors_bsdf_by_plugin(capsys):
    assert phonglab(["fit", "my_lambert", "--set", "reflectance=0.3", "--model", "lambert",
                     "--plugin", str(AUTHORS / "my_lambert.py"), "--variant", "llvm_ad_rgb"]) == 0
    assert "fitted  k_d = 0.3" in capsys.readouterr().out


@pytest.mark.parametrize("command", [["fit", "x"], ["check", "--only", "sanity", "--spp", "16"]])
def test_plugin_files_checked_before_work(command, tmp_path, capsys):
    fails_in_one_sentence(capsys, [*command, "--plugin", str(tmp_path / "missing.py")],
                          "does not exist")
    fails_in_one_sentence(capsys, [*command, "--plugin", str(tmp_path)], "is a folder")
    taken = tmp_path / "taken.py"
    taken.write_text((AUTHORS / "my_lambert.py").read_text().replace('"my_lambert"', '"diffuse"'))
    fails_in_one_sentence(capsys, [*command, "--plugin", str(taken)], "a name Mitsuba already has")


def test_integrator_returning_the_wrong_type_is_one_sentence_not_an_abort():
    """One sentence naming the method and its expected returns, exit 2 -- not an abort inside
    Dr.Jit (exit 134, "Referenced an unknown variable") with no report."""
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
def test_bsdf_returning_the_wrong_type_names_the_method(method, old, new, said, tmp_path,
                                                        capsys):
    text = (AUTHORS / "my_lambert.py").read_text()
    assert old in text
    bad = tmp_path / "bad.py"
    bad.write_text(text.replace(old, new).replace('"my_lambert"', '"bad_return"'))
    fails_in_one_sentence(capsys, ["validate", "bad_return", "--plugin", str(bad), "--quick",
                                   "--no-sweep", "--only", "finite", "--variant", "llvm_ad_rgb"],
                          said)


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


def test_phase_function_returning_the_wrong_type_names_the_method(tmp_path, capsys):
    """The method and what it returns are named, not "too many values to unpack (expected 2)"
    in every topic."""
    text = (HERE / "defects_phase" / "hg_control.py").read_text()
    assert "return mi.Spectrum(p), p" in text
    bad = tmp_path / "badphase.py"
    bad.write_text(text.replace("return mi.Spectrum(p), p", "return mi.Spectrum(p)")
                   .replace('mi.register_phase("defect_hg_control"',
                            'mi.register_phase("bad_phase_return"'))
    assert "bad_phase_return" in bad.read_text()
    fails_in_one_sentence(capsys, ["validate", "bad_phase_return", "--plugin", str(bad),
                                   "--quick", "--no-sweep", "--variant", "llvm_ad_rgb"],
                          "eval_pdf() of the phase function 'bad_phase_return' returned Color3f")


# --- every message whole -----------------------------------------------------------------------

def _as(tmp_path, name: str, source: Path = AUTHORS / "my_lambert.py") -> Path:
    """``source`` registered as ``name``, in tmp_path."""
    path = tmp_path / f"{name}.py"
    path.write_text(source.read_text().replace('"my_lambert"', repr(name)))
    return path


MY_POINT = '''import mitsuba as mi


class MyPoint(mi.Emitter):
    def __init__(self, props):
        mi.Emitter.__init__(self, props)
        self.m_flags = mi.EmitterFlags.DeltaPosition


mi.register_emitter("mypoint", lambda props: MyPoint(props))
'''


def test_check_says_which_parameters_it_sets_on_the_named_plugin(tmp_path, capsys):
    """The parameters check sets, by name -- not "cannot load BSDF 'mybp' (0.5, 0.5, 0.5])",
    a fragment of Mitsuba's list."""
    err = fails_in_one_sentence(capsys, ["check", "--phong", "mybp", "--plugin",
                                         str(_as(tmp_path, "mybp")), "--only", "sanity",
                                         "--no-progress"],
                                "check sets diffuse_reflectance and specular_reflectance",
                                "exponent", "--phong 'mybp'",
                                "does not read the parameters diffuse_reflectance, "
                                "specular_reflectance, exponent")
    assert "0.5])" not in err and "()" not in err


def test_check_names_an_emitter_given_as_the_lambertian(tmp_path, capsys):
    """'mypoint' is named an emitter, not a BSDF that cannot load with (0.7, 0.7, 0.7)."""
    (tmp_path / "mypoint.py").write_text(MY_POINT)
    fails_in_one_sentence(capsys, ["check", "--lambert", "mypoint", "--plugin",
                                   str(tmp_path / "mypoint.py"), "--only", "sanity",
                                   "--no-progress"], "'mypoint' is an emitter", "not a BSDF")
    fails_in_one_sentence(capsys, ["check", "--lambert", "point", "--only", "sanity",
                                   "--no-progress"], "'point' is a Mitsuba Emitter plugin")


@pytest.mark.parametrize("value", [0.5, "x", True, 3, [1, 2, 3], {"type": "rgb", "value": 0.2},
                                   {"type": "checkerboard"}],
                         ids=["float", "string", "bool", "int", "vector", "rgb", "texture"])
def test_a_parameter_the_plugin_never_reads_is_named_whatever_its_value(tmp_path, value,
                                                                        variant_llvm_rgb):
    """Mitsuba's list of unread properties was cut at the first '[' of a value ("1, 2, 3]")."""
    runpy.run_path(str(_as(tmp_path, "reads_one")))
    with pytest.raises(PluginError) as info:
        load_plugin({"type": "reads_one", "foo": value}, kind=mi.BSDF, word="BSDF")
    text = str(info.value)
    assert "the plugin 'reads_one' does not read the parameter foo" in text, text
    assert "()" not in text and "]" not in text, text


def test_a_loader_error_without_words_is_never_empty():
    assert mitsuba_reason(RuntimeError("")) == "RuntimeError without a message"
    assert mitsuba_reason(RuntimeError("[parser.cpp:1] At dictionary node \"root\": [")).strip()


RAISES = '''    def eval(self, ctx, si, wo, active=True):
        raise RuntimeError("boom")
'''


def _raising(tmp_path) -> Path:
    path = _as(tmp_path, "raise_rt")
    text = path.read_text()
    path.write_text(text.replace("    def eval(self, ctx, si, wo, active=True):\n", RAISES, 1))
    return path


def test_fit_of_a_plugin_that_raises_is_one_sentence(tmp_path, capsys):
    """One sentence naming the plugin's error and its line, not its traceback."""
    plugin = _raising(tmp_path)
    fails_in_one_sentence(capsys, ["fit", "raise_rt", "--plugin", str(plugin), "--model",
                                   "lambert", "--maxiter", "2"],
                          "the BSDF 'raise_rt' raised RuntimeError: boom (raise_rt.py:", "in eval)")


def test_the_full_check_of_a_plugin_that_raises_fails_its_rows(tmp_path, capsys):
    """`check --lambert` of it: each check it breaks is a failing row naming the plugin's
    error, and the others still report."""
    plugin = _raising(tmp_path)
    assert phonglab(["check", "--lambert", "raise_rt", "--plugin", str(plugin), "--spp", "8",
                     "--no-progress"]) == 1
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    assert "fail energy/energy: the check ran to completion: the plugin raised RuntimeError: " \
           "boom (raise_rt.py:" in out
    assert "pass    snell" in out                      # a check the plugin does not enter


def test_a_plugin_file_that_switches_the_variant_is_named_for_it(tmp_path, capsys):
    """Named for switching the variant, not reported as "registered nothing"."""
    path = _as(tmp_path, "switches")
    path.write_text(path.read_text().replace("import mitsuba as mi\n",
                                             "import mitsuba as mi\nmi.set_variant('scalar_rgb')\n",
                                             1))
    fails_in_one_sentence(capsys, ["validate", "switches", "--plugin", str(path), "--quick"],
                          "switched Mitsuba's variant to 'scalar_rgb' (mi.set_variant)",
                          "remove the mi.set_variant call")
    assert mi.variant() != "scalar_rgb"            # phonglab's variant is back


#: A tiny scene whose sphere is of the author's own BSDF type "mine".
SCENE_OF_MY_OWN = TINY.replace('<bsdf type="phong"/>', '<bsdf type="mine"/>')


def test_render_takes_the_authors_bsdf_by_plugin(tmp_path, capsys):
    """`render` had no --plugin: a scene with the author's own BSDF could not be rendered."""
    scene = tmp_path / "scene.xml"
    scene.write_text(SCENE_OF_MY_OWN)
    fails_in_one_sentence(capsys, ["render", str(scene), "-o", str(tmp_path / "a.exr")],
                          "no bsdf plugin named 'mine'", "--plugin FILE.py")
    out = tmp_path / "b.exr"
    assert phonglab(["render", str(scene), "--plugin", str(_as(tmp_path, "mine")), "-o",
                     str(out)]) == 0
    capsys.readouterr()
    image, meta = exr.read(out)
    assert image.mean() > 0.05 and meta["spp"] == 4
