"""No exit 0 without a verdict: a plugin that calls ``sys.exit`` or ``os._exit``, at import
or in a method, or that loops forever at import, ends as a failing row or as one sentence with a
non-zero exit status -- for ``validate``, ``check``, ``fit`` and :mod:`phonglab.testing` -- and
``--timeout`` covers loading the plugin file; a reader that closes the pipe (``| head``) ends
the output quietly, with the verdict's own status.

Two guards keep a regression from passing by accident, or from ending the test run itself
(:mod:`helpers`): ``os._exit`` is replaced for each test by a function that raises
``ProcessWouldEnd`` (a BaseException phonglab never catches), so a call that phonglab lets
through fails the test instead of ending pytest with status 0; a hang is bounded by a watchdog
thread that interrupts the main thread and fails the test.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from phonglab.testing import assert_bsdf_valid
from phonglab.validate.inputs import ValidateError

from helpers import acting_plugin, assert_no_green, refuse_process_exit, run_cli, watchdog

#: phonglab's sources for a subprocess (PHONGLAB_TEST_SRC: another tree, e.g. the code before a fix)
SOURCES = os.environ.get("PHONGLAB_TEST_SRC", str(Path(__file__).parent.parent / "src"))


@pytest.fixture(autouse=True)
def no_real_exit(monkeypatch):
    refuse_process_exit(monkeypatch)



def validate_options(timeout: int = 2) -> list[str]:
    return ["--quick", "--no-sweep", "--only", "finite", "--timeout", str(timeout), "--variant",
            "llvm_ad_rgb"]


VALIDATE = validate_options()


@pytest.mark.parametrize("place, action, said", [
    ("eval", "sys_exit", "sys.exit(0)"),           # exit 0, no report, no output
    ("sample", "sys_exit_3", "sys.exit(3)"),
    ("import", "sys_exit", "sys.exit(0)"),
    ("import", "os_exit", "os._exit(0)"),           # exit 0, no output
    ("eval", "os_exit", "os._exit(0)"),
    ("__init__", "os_exit", "os._exit(0)"),
    ("traverse", "sys_exit", "sys.exit(0)"),
])
def test_validate_never_exits_with_the_plugins_status(tmp_path, place, action, said):
    plugin = acting_plugin(tmp_path, place, action)
    rc, out, err = run_cli(["validate", plugin.stem, "--plugin", plugin, *VALIDATE])
    assert_no_green(rc, err)
    assert said in out + err and f"{plugin.name}" in out + err, out + err


@pytest.mark.parametrize("place", ["import", "__init__", "traverse"])
def test_validate_timeout_covers_loading(tmp_path, place):
    """A file that loops forever at import hung `validate --timeout 5`: the limit did not cover
    loading."""
    plugin = acting_plugin(tmp_path, place, "hang")
    # 1 s, not VALIDATE's 2: the plugin hangs whatever the limit (the limit is waited out)
    rc, out, err = run_cli(["validate", plugin.stem, "--plugin", plugin, *validate_options(1)],
                           seconds=60)
    assert rc == 2 and "did not finish" in err and "within 1 s" in err, out + err
    assert_no_green(rc, err)


def test_check_and_fit_never_exit_with_the_plugins_status(tmp_path):
    """`check` and `fit` exited 0 with no output when the plugin's eval called sys.exit(0)."""
    plugin = acting_plugin(tmp_path, "eval", "sys_exit")
    rc, out, err = run_cli(["check", "--lambert", plugin.stem, "--plugin", plugin, "--only",
                        "sanity", "--spp", "8", "--no-progress"])
    assert_no_green(rc, err)
    assert "sys.exit(0)" in out + err
    rc, out, err = run_cli(["fit", plugin.stem, "--plugin", plugin, "--model", "lambert",
                        "--maxiter", "2"])
    assert_no_green(rc, err)
    assert "sys.exit(0)" in err and plugin.name in err


@pytest.mark.parametrize("command", [
    ["check", "--lambert", "{name}", "--only", "sanity", "--spp", "8", "--no-progress"],
    ["fit", "{name}", "--model", "lambert", "--maxiter", "2"]], ids=["check", "fit"])
@pytest.mark.parametrize("place", ["import", "eval"])
def test_check_and_fit_take_a_timeout(tmp_path, command, place):
    """Neither had a time limit: a plugin that looped forever hung them."""
    plugin = acting_plugin(tmp_path, place, "hang")
    argv = [a.replace("{name}", plugin.stem) for a in command]
    rc, out, err = run_cli([*argv, "--plugin", plugin, "--timeout", "1"], seconds=90)
    assert_no_green(rc, err)
    assert "did not finish" in out + err and "within 1 s" in out + err, out + err


@pytest.mark.parametrize("command", [["check", "--no-progress"], ["fit", "x"]])
def test_a_timeout_that_is_not_positive_is_refused_before_work(command):
    rc, _, err = run_cli([*command, "--timeout", "0"])
    assert rc == 2 and "--timeout must be a number of seconds > 0" in err


@pytest.mark.parametrize("place, action, error", [
    ("eval", "sys_exit", AssertionError), ("eval", "os_exit", AssertionError),
    ("import", "os_exit", ValidateError), ("import", "hang", ValidateError)])
def test_the_pytest_helpers_never_end_the_test_process(tmp_path, place, action, error):
    plugin = acting_plugin(tmp_path, place, action)
    with watchdog(60), pytest.raises(error) as info:
        assert_bsdf_valid(plugin.stem, plugins=[plugin], sweep=False, quick=True,
                          topics=["finite"], timeout=1 if action == "hang" else 2)
    assert "exit" in str(info.value) or "did not finish" in str(info.value), info.value


def test_a_closed_pipe_ends_quietly_with_the_verdicts_status(tmp_path):
    """`validate ... | head -3` turned a PASS into exit 1 with a BrokenPipeError traceback."""
    out = tmp_path / "r.json"
    p = subprocess.Popen([sys.executable, "-m", "phonglab.cli", "validate", "diffuse", "--quick",
                          "--no-sweep", "--only", "finite", "--json", str(out)],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         env={**os.environ, "PYTHONPATH": SOURCES})
    p.stdout.close()             # the reader is gone before the first write (`| head -0`)
    err = p.stderr.read().decode()
    assert p.wait(timeout=300) == 0, err
    assert "Traceback" not in err and "BrokenPipe" not in err, err
    assert json.loads(out.read_text())["meta"]["bsdf"] == "diffuse"     # files still written
