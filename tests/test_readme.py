"""Every command the README shows runs in a test: the plugin-author example here, the install
section in tests/test_packaging.py (its commands, from a folder outside the checkout), `make
test` in CI itself, `make demo`'s render and `make docs` in the slow tier (here and in
tests/test_docs.py)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from helpers import run_cli

ROOT = Path(__file__).parent.parent
README = (ROOT / "README.md").read_text()
SRC = ROOT / "src"

#: The install section's commands (tests/test_packaging.py runs them, command for command).
INSTALL = {"python -m pip wheel", "python -m venv", "~/phonglab-env/bin/python -m pip install",
           "cd ~/my-project", "phonglab doctor", "phonglab check", "phonglab render cornell_phong",
           "phonglab validate mybsdf", "python -m pytest test_mybsdf.py"}
#: Where the others run.
ELSEWHERE = {"make demo": "test_make_demo_renders (slow)", "make test": ".ci/run (CI)"}


def commands() -> list[str]:
    """The command lines of the README's sh and text blocks (a text block's `$ ` lines)."""
    out = []
    for lang, body in re.findall(r"```(sh|text)\n(.*?)```", README, re.S):
        for line in body.splitlines():
            line = line.split("  #")[0].strip()
            if lang == "text":
                if not line.startswith("$ "):
                    continue
                line = line[2:]
            if line:
                out.append(line)
    return out


def test_every_readme_command_is_run_by_a_test():
    for c in commands():
        covered = (any(c.startswith(p) for p in INSTALL) or c in ELSEWHERE
                   or c in PLUGIN_AUTHOR)
        assert covered, f"README command {c!r} is run by no test: add it to a test"
    assert len(README.splitlines()) < 150


def _run(line: str):
    args = line.split()
    assert args[0] == "phonglab"
    return subprocess.run([sys.executable, "-m", "phonglab.cli", *args[1:]], cwd=ROOT,
                          capture_output=True, text=True, timeout=600,
                          env={**os.environ, "PYTHONPATH": str(SRC)})


#: The plugin-author example: command -> (exit code, text its output must hold).
PLUGIN_AUTHOR = {
    "phonglab validate tut_delta_importance --plugin tests/corpus/tut_delta_importance.py "
    "--quick": (1, "Importance mode: weight_Importance = η² · weight_Radiance (same u)"),
    "phonglab validate tut_delta --plugin tests/corpus/tut_delta.py --quick":
        (0, "tut_delta: PASSED"),
}


@pytest.mark.parametrize("line", sorted(PLUGIN_AUTHOR))
def test_the_plugin_author_example_runs_as_shown(line, monkeypatch):
    assert line in commands()
    rc, text = PLUGIN_AUTHOR[line]
    monkeypatch.chdir(ROOT)                   # the example's paths are the checkout's
    code, out, err = run_cli([*line.split()[1:], "--variant", "llvm_ad_rgb"])   # in-process
    assert code == rc, out[-2000:] + err[-2000:]
    assert text in out


@pytest.mark.slow
def test_make_demo_renders(tmp_path):
    """`make demo`'s render (the Makefile's demo target, set-up aside), into a temp folder."""
    make = (ROOT / "Makefile").read_text()
    line = re.search(r"^demo:.*\n\t\$\(BIN\)/(phonglab render .*)$", make, re.M).group(1)
    out = tmp_path / "demo.exr"
    r = _run(line.replace("out/demo.exr", str(out)))
    assert r.returncode == 0, r.stderr[-2000:]
    assert out.exists() and out.with_suffix(".png").exists()
