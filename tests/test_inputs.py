"""Every input answered before the work, across the commands: folders where files are expected,
every output path, symbolic links, time limits, and ``doctor`` telling the truth about the
libLLVM it loaded.  Outputs never harm what is there: for every output option of every
command, a device, FIFO or socket (or a link to one), an output that is one of the command's
inputs, an empty name and a name ending in '/' are refused before the work, and what was there
is left as it was."""

from __future__ import annotations

import importlib.util
import json
import os
import stat
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from phonglab import cli, planner
from phonglab.engine import exr
from phonglab.engine import outputs
from phonglab.errors import PlanError, WriteError

from helpers import SPECIAL_KINDS, make_special
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
        planner.PlanOptions(0.1, max_seconds=-1)


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


# --- outputs never harm what is there --------------------------------------------------------

#: Every output option of every command: (name, argv with {out} for the path, suffix, "file"
#: or "folder", the command's work (never reached when the path is refused)).
OUTPUT_SLOTS = [
    ("validate-json", ["validate", "diffuse", "--quick", "--no-sweep", "--json", "{out}"],
     ".json", "file", ("phonglab.cli.validate", "validate_one")),
    ("validate-report", ["validate", "diffuse", "--quick", "--no-sweep", "--report", "{out}"],
     ".html", "file", ("phonglab.cli.validate", "validate_one")),
    ("check-json", ["check", "--only", "snell", "--no-progress", "--json", "{out}"], ".json",
     "file", ("phonglab.checks", "run_checks")),
    ("check-out-dir", ["check", "--only", "snell", "--no-progress", "--out-dir", "{out}"], "",
     "folder", ("phonglab.checks", "run_checks")),
    ("fit-json", ["fit", "roughconductor", "--json", "{out}"], ".json", "file",
     ("phonglab.fit.optimize", "fit")),
    ("fit-report", ["fit", "roughconductor", "--report", "{out}"], ".txt", "file",
     ("phonglab.fit.optimize", "fit")),
    ("render-o", ["render", "gray_direct", "-o", "{out}"], ".exr", "file",
     ("phonglab.engine.render", "render_file")),
    ("compare-diff", ["compare", "{image}", "{image}", "--diff", "{out}"], ".png", "file",
     ("phonglab.engine.compare", "compare_files")),
    ("compare-models-o", ["compare-models", "gray_direct", "-o", "{out}"], "", "folder",
     ("phonglab.engine.compare_models", "compare_models")),
    ("bench-out", ["bench", "--quick", "--out", "{out}"], "", "folder",
     ("phonglab.bench.run", "run_bench")),
    ("bench-markdown", ["bench", "--quick", "--out", "{tmp}/b", "--markdown", "{out}"], ".md",
     "file", ("phonglab.bench.run", "run_bench")),
    ("bench-cache", ["bench", "--quick", "--out", "{tmp}/b", "--cache", "{out}"], "", "folder",
     ("phonglab.bench.run", "run_bench")),
]
FILE_SLOTS = [s for s in OUTPUT_SLOTS if s[3] == "file"]


def _slot_argv(argv, out, tmp_path) -> list[str]:
    image = tmp_path / "image.exr"
    if not image.exists():
        exr.write(image, np.full((4, 4, 3), 0.5, np.float32))
    return [a.replace("{out}", str(out)).replace("{tmp}", str(tmp_path))
            .replace("{image}", str(image)) for a in argv]


@pytest.mark.parametrize("kind", SPECIAL_KINDS)
@pytest.mark.parametrize("slot", OUTPUT_SLOTS, ids=[s[0] for s in OUTPUT_SLOTS])
def test_an_output_that_is_not_a_regular_file_is_refused_and_left_as_it_is(
        tmp_path, capsys, monkeypatch, slot, kind):
    """As root, `validate diffuse --json /dev/null` replaced the null device with a regular
    file (the atomic rename goes over whatever the path is); `--json /dev/full` exited 0."""
    _, argv, suffix, what, work = slot
    out = tmp_path / f"x{suffix}"
    before = make_special(out, kind)
    _no_work(monkeypatch, *work)
    _fails_in_one_sentence(capsys, _slot_argv(argv, out, tmp_path),
                           "not a regular file" if what == "file" else "not a folder")
    assert stat.S_IFMT(os.lstat(out).st_mode) == before


@pytest.mark.parametrize("slot", FILE_SLOTS, ids=[s[0] for s in FILE_SLOTS])
def test_a_link_to_a_device_is_refused_and_the_link_kept(tmp_path, capsys, monkeypatch, slot):
    _, argv, suffix, _, work = slot
    device = tmp_path / "dev"
    before = make_special(device, "char_device" if os.geteuid() == 0 else "fifo")
    link = tmp_path / f"link{suffix}"
    link.symlink_to(device)
    _no_work(monkeypatch, *work)
    _fails_in_one_sentence(capsys, _slot_argv(argv, link, tmp_path), "a symbolic link to",
                           "not a regular file")
    assert link.is_symlink() and stat.S_IFMT(os.lstat(device).st_mode) == before


@pytest.mark.parametrize("slot", OUTPUT_SLOTS, ids=[s[0] for s in OUTPUT_SLOTS])
def test_an_empty_output_name_is_refused(tmp_path, capsys, monkeypatch, slot):
    """`validate diffuse --json ""` validated, wrote nothing and exited 0."""
    _, argv, _, _, work = slot
    _no_work(monkeypatch, *work)
    _fails_in_one_sentence(capsys, _slot_argv(argv, "", tmp_path), "is an empty name")


@pytest.mark.parametrize("slot", FILE_SLOTS, ids=[s[0] for s in FILE_SLOTS])
def test_an_output_file_name_ending_in_a_slash_is_refused(tmp_path, capsys, monkeypatch, slot):
    """`validate ... --json newdir/` (a folder that does not exist) wrote a file named newdir."""
    _, argv, suffix, _, work = slot
    _no_work(monkeypatch, *work)
    _fails_in_one_sentence(capsys, _slot_argv(argv, f"{tmp_path}/newdir{suffix}/", tmp_path),
                           "ends in '/'")
    assert not (tmp_path / f"newdir{suffix}").exists()


VICTIM = (Path(__file__).parent / "authors" / "my_lambert.py").read_text()


@pytest.mark.parametrize("case", [
    # the plugin's source was overwritten with the JSON report
    (["validate", "my_lambert", "--plugin", "{victim}", "--json", "{victim}"],
     ("phonglab.cli.validate", "validate_one"), "same"),
    (["validate", "my_lambert", "--plugin", "{victim}", "--report", "{out}.html"],
     ("phonglab.cli.validate", "validate_one"), "hardlink"),
    (["validate", "my_lambert", "--plugin", "{victim}", "--json", "{out}.json"],
     ("phonglab.cli.validate", "validate_one"), "symlink"),
    (["fit", "my_lambert", "--plugin", "{victim}", "--report", "{victim}"],
     ("phonglab.fit.optimize", "fit"), "same"),
    (["fit", "my_lambert", "--plugin", "{victim}", "--json", "{out}.json"],
     ("phonglab.fit.optimize", "fit"), "symlink"),
    (["check", "--lambert", "my_lambert", "--plugin", "{victim}", "--json", "{victim}"],
     ("phonglab.checks", "run_checks"), "same"),
    (["render", "{scene}", "--plugin", "{victim}", "-o", "{out}.exr"],
     ("phonglab.engine.render", "render_file"), "hardlink"),
    (["render", "{scene}", "-o", "{out}.exr"], ("phonglab.engine.render", "render_file"),
     "scene"),
    (["compare", "{victim}", "{victim}", "--diff", "{out}.png"],
     ("phonglab.engine.compare", "compare_files"), "hardlink"),
], ids=["validate-json", "validate-report-hardlink", "validate-json-symlink", "fit-report",
        "fit-json-symlink", "check-json", "render-plugin-hardlink", "render-scene-hardlink",
        "compare-diff-hardlink"])
def test_an_output_that_is_one_of_the_inputs_is_refused(tmp_path, capsys, monkeypatch, case):
    """`validate mybp --plugin victim.py --json victim.py` overwrote the plugin's source."""
    argv, work, how = case
    victim = tmp_path / "victim.py"
    victim.write_text(VICTIM)
    scene = tmp_path / "scene.xml"
    scene.write_text(TINY_SCENE)
    out = tmp_path / "out"
    target = scene if how == "scene" else victim
    for suffix in (".html", ".json", ".exr", ".png"):
        if how in ("hardlink", "scene"):
            os.link(target, f"{out}{suffix}")
        elif how == "symlink":
            Path(f"{out}{suffix}").symlink_to(target)
    _no_work(monkeypatch, *work)
    argv = [a.replace("{victim}", str(victim)).replace("{out}", str(out))
            .replace("{scene}", str(scene)) for a in argv]
    _fails_in_one_sentence(capsys, argv, "one of this command's inputs")
    assert victim.read_text() == VICTIM and scene.read_text() == TINY_SCENE


def test_json_and_report_of_one_run_may_not_be_the_same_file(tmp_path, capsys, monkeypatch):
    _no_work(monkeypatch, "phonglab.fit.optimize", "fit")
    same = str(tmp_path / "r.txt")
    _fails_in_one_sentence(capsys, ["fit", "roughconductor", "--json", same, "--report", same],
                           "are the same file")


def test_the_log_beside_an_all_builtins_json_is_checked_too(tmp_path, capsys, monkeypatch):
    make_special(tmp_path / "c.json.partial.jsonl", "fifo")
    _no_work(monkeypatch, "phonglab.validate.batch", "run_all")
    _fails_in_one_sentence(capsys, ["validate", "--all-builtins", "--quick", "--json",
                                    str(tmp_path / "c.json")], "not a regular file")
    assert stat.S_ISFIFO(os.lstat(tmp_path / "c.json.partial.jsonl").st_mode)


def test_a_link_to_a_regular_file_is_written_through(tmp_path, capsys):
    """The one kind of output that is not a plain name and is what the user meant."""
    (tmp_path / "real.json").write_text("{}")
    (tmp_path / "link.json").symlink_to("real.json")
    assert cli.main(["validate", "diffuse", "--quick", "--no-sweep", "--only", "finite",
                     "--json", str(tmp_path / "link.json")]) == 0
    capsys.readouterr()
    assert (tmp_path / "link.json").is_symlink()
    assert json.loads((tmp_path / "real.json").read_text())["meta"]["bsdf"] == "diffuse"


@pytest.mark.parametrize("kind", SPECIAL_KINDS)
def test_the_write_itself_never_renames_over_anything_but_a_regular_file(tmp_path, kind):
    """The last line of defence, for a path that became a device after the checks ran."""
    path = tmp_path / "x.json"
    before = make_special(path, kind)
    with pytest.raises(WriteError, match="not a regular file"):
        outputs.write_json(path, {"a": 1})
    assert stat.S_IFMT(os.lstat(path).st_mode) == before
    assert [p.name for p in tmp_path.iterdir()] == ["x.json"]      # no temporary left
