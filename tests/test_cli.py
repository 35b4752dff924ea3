"""The command line: every bad input is one sentence with the fix and exit code 2, never a
traceback (``--debug`` shows it); every help text shows an example.

The cases run ``phonglab.cli.main([...])`` in-process (fast) and capture stderr; one case runs
the installed ``phonglab`` script in a subprocess, as a user would.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from phonglab import cli

from phonglab.engine import exr

UNKNOWN_PY_PARAM = """<scene version="3.0.0">
  <bsdf type="phong" id="a"><float name="exponant" value="3"/></bsdf>
  <shape type="sphere"><ref id="a"/></shape>
</scene>
"""
UNKNOWN_BUILTIN_PARAM = """<scene version="3.0.0">
  <bsdf type="diffuse" id="a"><rgb name="reflectanse" value="0.3"/></bsdf>
  <shape type="sphere"><ref id="a"/></shape>
</scene>
"""
MALFORMED = """<scene version="3.0.0">
  <bsdf type="diffuse" id="a">
  <shape type="sphere"><ref id="a"/></shape>
</scene>
"""
UNKNOWN_PLUGIN = """<scene version="3.0.0">
  <bsdf type="phongg" id="a"/>
  <shape type="sphere"><ref id="a"/></shape>
</scene>
"""
UNPHYSICAL = """<scene version="3.0.0">
  <bsdf type="phong" id="a">
    <float name="diffuse_reflectance" value="0.7"/>
    <float name="specular_reflectance" value="0.5"/>
  </bsdf>
  <shape type="sphere"><ref id="a"/></shape>
</scene>
"""


def _files(tmp_path: Path) -> dict[str, Path]:
    out = {}
    for name, text in [("unknown_py_param", UNKNOWN_PY_PARAM),
                       ("unknown_builtin_param", UNKNOWN_BUILTIN_PARAM),
                       ("malformed", MALFORMED), ("unknown_plugin", UNKNOWN_PLUGIN),
                       ("unphysical", UNPHYSICAL)]:
        out[name] = tmp_path / f"{name}.xml"
        out[name].write_text(text)
    out["png"] = tmp_path / "not_an.exr"
    out["png"].write_bytes(b"\x89PNG\r\n\x1a\n" + b"\0" * 64)
    out["small"] = exr.write(tmp_path / "small.exr", np.zeros((4, 5, 3)))
    out["large"] = exr.write(tmp_path / "large.exr", np.zeros((4, 6, 3)))
    return out


#: (id, argv with {placeholders} for _files, regexes the message must match)
CASES = [
    ("missing-scene", ["render", "{tmp}/nope.xml"],
     [r"scene file not found: .*nope\.xml", r"give a path to a Mitsuba XML file"]),
    ("malformed-xml", ["render", "{malformed}"],
     [r"malformed\.xml, line 4: malformed XML", r"fix the markup"]),
    ("unknown-param-python-plugin", ["render", "{unknown_py_param}"],
     [r"line 2: the bsdf plugin 'phong' has no parameter 'exponant'",
      r"did you mean 'exponent'\?", r"fix the spelling or remove it"]),
    ("unknown-param-builtin", ["render", "{unknown_builtin_param}"],
     [r"line 2: the bsdf plugin 'diffuse' has no parameter 'reflectanse'",
      r"fix the spelling or remove it"]),
    ("unknown-plugin", ["render", "{unknown_plugin}"],
     [r"no bsdf plugin named 'phongg' \(did you mean 'phong'\?\)"]),
    ("unknown-variant", ["render", "nb_emitter_distance", "--variant", "llvm_ad_rbg"],
     [r"unknown Mitsuba variant 'llvm_ad_rbg'", r"choose one of .*llvm_ad_rgb"]),
    ("unphysical-material", ["render", "{unphysical}"],
     [r"line 2: phong: diffuse_reflectance \[0\.7.*\+ specular_reflectance \[0\.5.* exceeds 1",
      r"Lower 'diffuse_reflectance' or 'specular_reflectance'"]),
    ("compare-missing-file", ["compare", "{tmp}/nope.exr", "{small}"],
     [r"no such EXR file: .*nope\.exr; check the path"]),
    ("compare-not-exr", ["compare", "{png}", "{small}"],
     [r"not_an\.exr is not an OpenEXR file", r"give the \.exr file"]),
    ("compare-mismatched-shapes", ["compare", "{small}", "{large}"],
     [r"small\.exr is 4 x 5 x 3 but .*large\.exr is 4 x 6 x 3", r"same resolution"]),
    ("compare-one-stderr", ["compare", "{small}", "{small}", "--stderr-a", "{small}"],
     [r"--stderr-a was given without --stderr-b"]),
    ("compare-diff-not-png", ["compare", "{small}", "{small}", "--diff", "{small}"],
     [r"--diff writes a PNG image, but .*small\.exr does not end in \.png"]),
    ("compare-folder", ["compare", "{tmp}", "{small}"], [r"is a folder, not an EXR file"]),
    ("render-output-folder", ["render", "nb_emitter_distance", "-o", "{tmp}"],
     [r"the output must be a file name ending in \.exr"]),
    ("render-zero-spp", ["render", "nb_emitter_distance", "--spp", "0"],
     [r"spp \(samples per pixel\) must be >= 1, got 0; ask for at least one sample"]),
]


def _argv(argv, files, tmp_path):
    fmt = {k: str(v) for k, v in files.items()}
    fmt["tmp"] = str(tmp_path)
    return [a.format(**fmt) for a in argv] + (["-o", str(tmp_path / "out.exr")]
                                              if argv[0] == "render" and "-o" not in argv else [])


@pytest.mark.parametrize("argv, patterns", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_bad_input_is_one_sentence_and_exit_2(tmp_path, capsys, argv, patterns, variant_llvm_rgb):
    files = _files(tmp_path)
    rc = cli.main(_argv(argv, files, tmp_path))
    err = capsys.readouterr().err.strip()
    assert rc == 2, err
    assert "Traceback" not in err
    lines = err.splitlines()
    assert len(lines) == 1, f"expected one line, got:\n{err}"
    assert lines[0].startswith("phonglab: error: ")
    for pattern in patterns:
        assert re.search(pattern, lines[0]), (pattern, lines[0])
    assert not (tmp_path / "out.exr").exists()


@pytest.mark.parametrize("where", ["before", "after"])
def test_debug_shows_the_traceback(tmp_path, where, variant_llvm_rgb, capsys):
    """--debug adds the traceback and keeps the exit status (2 stays 2, not 1)."""
    bad = _files(tmp_path)["unknown_py_param"]
    argv = ["--debug", "render", str(bad)] if where == "before" else ["render", str(bad), "--debug"]
    assert cli.main(argv) == 2
    err = capsys.readouterr().err
    assert "Traceback (most recent call last)" in err and "SceneError" in err, err
    assert err.strip().splitlines()[-1].startswith("phonglab: error: ")
    assert "has no parameter 'exponant'" in err.strip().splitlines()[-1]


def test_real_subprocess(tmp_path):
    """The installed script, as a user runs it: one line, exit 2; with --debug a traceback."""
    exe = Path(sys.executable).with_name("phonglab")
    bad = _files(tmp_path)["malformed"]
    env = {**os.environ, "PYTHONWARNINGS": "ignore"}
    p = subprocess.run([str(exe), "render", str(bad)], capture_output=True, text=True, env=env,
                       timeout=120)
    assert p.returncode == 2
    assert p.stderr.strip().splitlines() == [
        f"phonglab: error: {bad}, line 4: malformed XML (mismatched tag); fix the markup there "
        f"(an unclosed or mismatched tag, or a stray character)."]
    p = subprocess.run([str(exe), "--debug", "render", str(bad)], capture_output=True, text=True,
                       env=env, timeout=120)
    assert p.returncode == 2 and "Traceback (most recent call last)" in p.stderr


def test_compare_end_to_end(tmp_path, capsys):
    b = np.full((6, 8, 3), 0.5, np.float32)
    a = b + np.float32(0.1)
    exr.write(tmp_path / "a.exr", a, {"spp": 4, "variant": "llvm_ad_rgb", "scene_sha256": "1"})
    exr.write(tmp_path / "b.exr", b, {"scene_sha256": "2"})
    rc = cli.main(["compare", str(tmp_path / "a.exr"), str(tmp_path / "b.exr"),
                   "--diff", str(tmp_path / "d.png")])
    out = capsys.readouterr().out
    assert rc == 0
    assert "RMSE        : 0.1" in out and "4 spp, llvm_ad_rgb" in out
    assert "note: A and B were rendered from different scene files" in out
    assert (tmp_path / "d.png").read_bytes()[:4] == b"\x89PNG"


# ------------------------------------------------------------------------------ help texts
def test_top_level_help_lists_an_example_of_every_subcommand(capsys):
    with pytest.raises(SystemExit) as exc:
        cli.main(["--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    assert "examples:" in out
    for name in cli.SUBCOMMANDS:
        assert f"\n  phonglab {name}" in out, f"no example of `phonglab {name}` in --help"


@pytest.mark.parametrize("name", cli.SUBCOMMANDS)
def test_subcommand_help_shows_an_example(capsys, name):
    with pytest.raises(SystemExit) as exc:
        cli.main([name, "--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    assert "example" in out
    # RawDescriptionHelpFormatter keeps the example on its own line, as typed.
    assert any(line.startswith(f"  phonglab {name}") for line in out.splitlines()), out


def test_no_command_prints_help_and_exits_2(capsys):
    assert cli.main([]) == 2
    assert "usage: phonglab" in capsys.readouterr().out


# --- messages whole -----------------------------------------------------------------------------

def test_plan_makes_a_reference_as_the_readme_says(tmp_path, monkeypatch, capsys):
    """`plan gray_direct --make-reference 16` makes the reference and plans against it."""
    from phonglab.engine import references

    monkeypatch.setattr(references, "CACHE_DIR", tmp_path / "cache")
    assert cli.main(["plan", "gray_direct", "--make-reference", "16", "-D", "res=8"]) == 0
    assert "reference: 16 spp" in capsys.readouterr().out
    assert list((tmp_path / "cache" / "references").glob("gray_direct-*.exr"))


def test_a_given_depth_whose_bias_alone_misses_the_target_is_one_sentence(capsys, tmp_path):
    """`render cornell_phong --target-error 0.05 --max-depth 3`: the bias of depth 3 alone
    exceeds E, so E² − bias² is negative; the planner says so in one sentence, exit 2 (no
    "math domain error" from its root)."""
    assert cli.main(["render", "cornell_phong", "--target-error", "0.05", "--max-depth", "3",
                     "-D", "res=16", "-o", str(tmp_path / "c.exr")]) == 2
    err = capsys.readouterr().err.split("\r")[-1].strip()
    assert err.startswith("phonglab: error: max_depth 3 omits a relative RMS") and \
        "more than the target error 0.05" in err and "\n" not in err, err
    assert not (tmp_path / "c.exr").exists()
