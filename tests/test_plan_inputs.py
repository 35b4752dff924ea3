"""Absurd plans are refused before anything renders (phonglab.planner)."""

from __future__ import annotations


from phonglab import cli, planner

from helpers import WHITTED_NO_DEPTH_DEFAULT, fails_in_one_sentence as _fails_in_one_sentence, write as _write


# --- absurd plans are refused before anything renders ------------------------------------------

def test_an_absurd_target_is_refused_by_plan_and_render(tmp_path, capsys):
    _fails_in_one_sentence(capsys, ["plan", "gray_direct", "--target-error", "1e-9", "--set",
                                    "res=16"], "more than a render takes")
    out = tmp_path / "x.exr"
    _fails_in_one_sentence(capsys, ["render", "gray_direct", "--target-error", "1e-9", "-o",
                                    str(out)], "more than a render takes")
    assert not out.exists()


def test_a_plan_over_the_time_limit_is_refused_unless_allowed(capsys):
    argv = ["plan", "gray_direct", "--target-error", "0.01", "--set", "res=16"]
    _fails_in_one_sentence(capsys, argv + ["--max-seconds", "1e-6"], "over the limit",
                           "--max-seconds")
    assert cli.main(argv + ["--max-seconds", "inf"]) == 0


def test_a_plugin_error_during_the_render_is_the_plugins_sentence(tmp_path, capsys):
    """whitted refuses an unknown ambient_reflectance_<id> at render time; Dr.Jit wraps that in
    its custom-operation RuntimeError, which render_scene unwraps."""
    scene = _write(tmp_path, "w.xml", WHITTED_NO_DEPTH_DEFAULT.replace(
        '<string name="units" value="graphics"/>',
        '<rgb name="ambient_reflectance_nope" value="0.3"/>'))
    _fails_in_one_sentence(capsys, ["render", str(scene), "-o", str(tmp_path / "w.exr")],
                           "ambient_reflectance_nope")


def test_a_planned_render_checks_its_outputs_before_the_pilot(tmp_path, capsys, monkeypatch):
    def no_pilot(*args, **kwargs):
        raise AssertionError("the plan was made although the output cannot be written")

    monkeypatch.setattr(planner, "plan", no_pilot)
    (tmp_path / "x.png").mkdir()
    _fails_in_one_sentence(capsys, ["render", "gray_direct", "--target-error", "0.05", "-o",
                                    str(tmp_path / "x.exr")], "is a folder")
