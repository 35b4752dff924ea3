"""Every input answered before the work, across the commands: folders where files are expected,
every output path, symbolic links, time limits, and ``doctor`` telling the truth about the
libLLVM it loaded."""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from phonglab import cli, planner
from phonglab.engine import exr
from phonglab.errors import PlanError

from helpers import fails_in_one_sentence as _fails_in_one_sentence


# --- every input answered before the work: folders, outputs, links, limits, libLLVM -----------

TINY_SCENE = '<scene version="3.0.0"><shape type="sphere"/></scene>'


def _no_work(monkeypatch, target: str, name: str) -> None:
    """``target.name`` (the command's work) fails the test if it is reached."""
    def work(*args, **kwargs):
        raise AssertionError(f"{target}.{name} ran although an input was bad")

    monkeypatch.setattr(importlib.import_module(target), name, work)


@pytest.mark.parametrize("command", [["render"], ["plan"], ["compare-models"]])
def test_a_folder_given_as_the_scene_is_called_a_folder(tmp_path, capsys, command):
    """It was 'scene file not found' followed by the list of shipped scenes."""
    (tmp_path / "scenes").mkdir()
    (tmp_path / "scenes" / "a.xml").write_text(TINY_SCENE)
    err = _fails_in_one_sentence(capsys, [*command, str(tmp_path / "scenes")], "is a folder",
                                 str(tmp_path / "scenes" / "a.xml"))
    assert "not found" not in err


@pytest.mark.parametrize("argv, work, words", [
    # written after all the checks had run (and failed with the checks' results lost)
    (["check", "--only", "snell", "--json", "/proc/c.json"], ("phonglab.checks", "run_checks"),
     ["/proc", "read-only", "JSON file"]),
    (["check", "--only", "snell", "--json", "{tmp}/"], ("phonglab.checks", "run_checks"),
     ["ends in '/'", "names a folder"]),
    (["check", "--only", "snell", "--out-dir", "{tmp}/file"], ("phonglab.checks", "run_checks"),
     ["is a file, not a folder"]),
    # a FileExistsError traceback from mkdir
    (["bench", "--quick", "--out", "{tmp}/file"], ("phonglab.bench.run", "run_bench"),
     ["is a file, not a folder", "--out"]),
    # "[Errno 2] No such file or directory: '/proc/bench'"
    (["bench", "--quick", "--out", "/proc/bench"], ("phonglab.bench.run", "run_bench"),
     ["/proc", "read-only", "--out"]),
    (["bench", "--quick", "--out", "{tmp}/b", "--markdown", "/proc/b.md"],
     ("phonglab.bench.run", "run_bench"), ["/proc", "read-only", "--markdown"]),
    # silently ignored: the report then quoted no quick run
    (["bench", "--quick", "--out", "{tmp}/b", "--quick-run", "{tmp}"],
     ("phonglab.bench.run", "run_bench"), ["is a folder", "--quick-run"]),
    (["bench", "--quick", "--out", "{tmp}/b", "--quick-run", "{tmp}/none.json"],
     ("phonglab.bench.run", "run_bench"), ["does not exist", "--quick-run"]),
    # a FileExistsError traceback after the three renders
    (["compare-models", "gray_direct", "-o", "{tmp}/file"],
     ("phonglab.engine.compare_models", "compare_models"), ["is a file, not a folder", "-o"]),
    # wrote the report as a file named like the folder
    (["fit", "roughconductor", "--report", "{tmp}/rep/"], ("phonglab.fit.optimize", "fit"),
     ["ends in '/'", "--report"]),
    (["fit", "roughconductor", "--json", "/proc/f.json"], ("phonglab.fit.optimize", "fit"),
     ["/proc", "read-only", "--json"]),
], ids=["check-json-proc", "check-json-folder", "check-out-dir-file", "bench-out-file",
        "bench-out-proc", "bench-markdown-proc", "bench-quick-run-folder",
        "bench-quick-run-missing", "compare-models-out-file", "fit-report-folder",
        "fit-json-proc"])
def test_every_output_is_checked_before_the_work(tmp_path, capsys, monkeypatch, argv, work,
                                                 words):
    (tmp_path / "file").write_text("keep")
    _no_work(monkeypatch, *work)
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    err = _fails_in_one_sentence(capsys, argv, *words)
    assert "Errno" not in err, err
    assert (tmp_path / "file").read_text() == "keep"
    assert not (tmp_path / "rep").exists() and not (tmp_path / "b").exists()


def test_an_output_that_is_a_symlink_is_written_through_the_link(tmp_path, capsys):
    """The atomic rename replaced the link with a regular file, leaving its target stale."""
    (tmp_path / "real.json").write_text("{}")
    (tmp_path / "link.json").symlink_to("real.json")
    assert cli.main(["check", "--only", "snell", "--spp", "16", "--json",
                     str(tmp_path / "link.json")]) == 0
    assert (tmp_path / "link.json").is_symlink()
    assert json.loads((tmp_path / "real.json").read_text())["results"]
    (tmp_path / "link.exr").symlink_to("real.exr")          # dangling: made through it
    assert cli.main(["render", "gray_direct", "-D", "res=8", "--spp", "2", "-o",
                     str(tmp_path / "link.exr")]) == 0
    assert (tmp_path / "link.exr").is_symlink() and exr.read(tmp_path / "real.exr")[0].size
    capsys.readouterr()


def test_a_symlink_to_a_folder_is_a_folder_for_the_output_checks(tmp_path, capsys):
    (tmp_path / "d").mkdir()
    (tmp_path / "x.json").symlink_to("d")
    _fails_in_one_sentence(capsys, ["check", "--only", "snell", "--json",
                                    str(tmp_path / "x.json")], "is a folder")


@pytest.mark.parametrize("command", [["render", "gray_direct", "--target-error", "0.1"],
                                     ["plan", "gray_direct"]])
@pytest.mark.parametrize("bad", ["-1", "0", "nan"])
def test_a_time_limit_that_is_not_positive_is_refused_before_any_work(command, bad, capsys,
                                                                       monkeypatch):
    """`render --max-seconds -1` ran the pilot, then refused every plan as over the limit."""
    _no_work(monkeypatch, "phonglab.planner", "plan")
    _fails_in_one_sentence(capsys, [*command, "--max-seconds", bad],
                           "--max-seconds must be a positive number of seconds")


def test_the_planner_refuses_a_time_limit_that_is_not_positive():
    with pytest.raises(PlanError, match="positive number of seconds"):
        planner.plan("gray_direct", 0.1, max_seconds=-1)


@pytest.mark.parametrize("library, words", [
    ("text", "is not a shared library"),         # /etc/passwd: "using /etc/passwd", exit 0
    ("folder", "is a folder"),
    ("elf", "could not be loaded by Dr.Jit"),    # a real shared library that is not libLLVM
])
def test_doctor_fails_when_the_libllvm_path_is_not_a_libllvm(tmp_path, library, words):
    import _ctypes

    path = {"text": tmp_path / "passwd", "folder": tmp_path,
            "elf": Path(_ctypes.__file__)}[library]
    (tmp_path / "passwd").write_text("root:x:0:0:root:/root:/bin/bash\n")
    done = subprocess.run([sys.executable, "-m", "phonglab.cli", "doctor"], capture_output=True,
                          text=True, timeout=120,
                          env={**os.environ, "DRJIT_LIBLLVM_PATH": str(path)})
    assert done.returncode == 1, done.stdout
    line = next(l for l in done.stdout.splitlines() if l.startswith("libLLVM"))
    assert words in line and "using" not in line, line
    assert "variant : scalar_rgb" in done.stdout
