"""The integrator validator: the control path tracer passes, each planted defect fails its own
topic (bias or finite; the double count also agreement: its box has an area light, which any
scene testing MIS must have), the analytic values hold, and the command line detects an
integrator.  Quick sizes, seed 0; α = 0.01 per integrator (Šidák)."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import pytest

from helpers import run_cli

DEFECTS = Path(__file__).parent / "defects_integrator"
SRC = Path(__file__).parents[1] / "src"

#: defect file -> the topics it must fail (empty: the control)
PLANTED = {
    "path_control": set(),
    "rr_forgets_q": {"bias"},
    "throughput_clamp": {"bias"},
    "nan_grazing": {"finite"},
    "direct_double_count": {"bias", "agreement"},
    # no FIXED_DEPTH: the depth is measured (2 for the control; none for the double count,
    # whose depth-dependent scenes and agreement are then skipped)
    "direct_undeclared": set(),
    "direct_double_count_undeclared": {"bias"},
}


#: the default tier runs these two (~6 s); the slow tier every defect
FAST = {"path_control", "nan_grazing", "direct_undeclared", "direct_double_count_undeclared"}


@pytest.mark.parametrize("name", [n if n in FAST else pytest.param(n, marks=pytest.mark.slow)
                                  for n in sorted(PLANTED)])
def test_defect_fails_its_topic_only(variant_llvm_rgb, name):
    from phonglab.validate import validate_integrator

    report = validate_integrator(f"defect_{name}", plugins=[DEFECTS / f"{name}.py"], quick=True)
    assert {r.topic for r in report.failing} == PLANTED[name], report.table(report.failing)


def test_plane_values_are_the_solid_angle():
    from phonglab.validate.integrator import scenes

    assert scenes.plane_pixels(32).mean() == pytest.approx(scenes.plane_value(), rel=1e-12)
    assert scenes.plane_value() < scenes.PLANE_RHO * scenes.PLANE_I / math.pi
    assert scenes.enclosure_value(0.5, 2) == pytest.approx(scenes.LE * 1.5)
    assert scenes.glass_deficit(64, 16) < 1e-5 < scenes.glass_deficit(4, 16)


def test_depth_detection(variant_llvm_rgb):
    from phonglab.validate import loading, registry
    kind = registry.by_name("integrator")

    def prepare(spec):
        return loading.prepare(kind, spec)

    t = {n: prepare(n).plugin for n in ("path", "direct", "direct_projective", "ptracer")}
    assert t["path"].depth == "settable"
    assert (t["direct"].depth, t["direct"].fixed_depth) == ("fixed", 2)
    assert (t["direct_projective"].depth, t["direct_projective"].fixed_depth) == ("fixed", 2)
    assert t["ptracer"].splatting and t["direct_projective"].ad
    aov = prepare({"type": "aov", "aovs": "nn:sh_normal"}).plugin
    assert aov.aov


def test_undeclared_depth_is_measured(variant_llvm_rgb):
    from phonglab.validate import validate_integrator

    report = validate_integrator("defect_direct_undeclared",
                                 plugins=[DEFECTS / "direct_undeclared.py"], quick=True,
                                 topics=["bias"])
    depth = [r for r in report.rows if r.name.startswith("depth measured")]
    assert [r.details["measured_depth"] for r in depth] == [2, 2], report.table()
    judged = {r.name for r in report.rows if r.status == "pass"}
    assert {"enclosure ρ=0.5 D=2", "enclosure ρ=0.8 D=2"} <= judged, report.table()
    bad = validate_integrator("defect_direct_double_count_undeclared",
                              plugins=[DEFECTS / "direct_double_count_undeclared.py"],
                              quick=True, topics=["bias"])
    assert {r.name for r in bad.failing} == {"depth measured: enclosure ρ=0.5",
                                             "depth measured: enclosure ρ=0.8"}, bad.table()
    assert all("matches no integer depth" in r.reason for r in bad.failing)


def test_aov_is_checked_for_finite_only(variant_llvm_rgb):
    from phonglab.validate import validate_integrator

    report = validate_integrator({"type": "aov", "aovs": "nn:sh_normal"}, quick=True,
                                 topics=["finite", "bias"])
    assert report.passed, report.table(report.failing)
    assert {r.status for r in report.rows if r.topic == "bias"} == {"skipped"}


def test_cli_detects_an_integrator_and_fails_a_defect(tmp_path):
    env = {"PYTHONPATH": str(SRC), "PATH": "/usr/bin:/bin"}
    out = tmp_path / "path.json"
    proc = subprocess.run([sys.executable, "-m", "phonglab.cli", "validate", "path", "--quick",
                           "--only", "bias", "--json", str(out)], capture_output=True,
                          text=True, env=env)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    import json
    assert json.loads(out.read_text())["meta"]["integrator"] == "path"
    proc = subprocess.run([sys.executable, "-m", "phonglab.cli", "validate",
                           "defect_rr_forgets_q", "--plugin", str(DEFECTS / "rr_forgets_q.py"),
                           "--quick", "--only", "bias"], capture_output=True, text=True, env=env)
    assert proc.returncode == 1, proc.stdout + proc.stderr


def test_assert_integrator_valid(variant_llvm_rgb):
    from phonglab.testing import assert_integrator_valid

    with pytest.raises(AssertionError, match="enclosure"):
        assert_integrator_valid("defect_rr_forgets_q", plugins=[DEFECTS / "rr_forgets_q.py"],
                                quick=True, topics=["bias"])


@pytest.mark.slow
@pytest.mark.parametrize("name", ["path", "direct", "volpath", "ptracer", "prb"])
def test_builtins_pass_default(variant_llvm_rgb, name):
    from phonglab.validate import validate_integrator

    report = validate_integrator(name)
    assert report.passed, report.table(report.failing)


def test_not_covered_exits_3_unless_allowed():
    """A topic that applies and judged nothing (agreement of an integrator whose measured depth
    matches no integer depth) is "not covered": exit 3, 0 with --allow-uncovered."""
    base = ["validate", "defect_direct_double_count_undeclared", "--plugin",
            DEFECTS / "direct_double_count_undeclared.py", "--quick", "--only", "agreement",
            "--variant", "llvm_ad_rgb"]
    rc, out, err = run_cli(base)
    assert rc == 3, out + err
    assert "NOT COVERED: agreement" in out and "FIXED_DEPTH = 2" in out
    rc, out, err = run_cli(base + ["--allow-uncovered"])
    assert rc == 0, out + err


def test_not_covered_rule():
    """Informational topics and skips marked not_applicable never count; any other topic whose
    rows are all skipped (or which has none) does."""
    from phonglab.validate.core import not_covered
    from phonglab.validate.integrator import KIND
    from phonglab.validate.integrator.topics import Row
    from phonglab.verdict import NOT_APPLICABLE

    def row(topic, status, na=False):
        return Row(topic, "x", None, None, None, None, status, "why",
                   {NOT_APPLICABLE: True} if na else {})

    rows = [row("finite", "pass"), row("bias", "skipped"), row("bias", "fail"),
            row("convergence", "skipped"), row("gradient", "skipped", na=True),
            row("cost", "skipped")]
    assert not_covered(KIND, KIND.topics, rows) == ["convergence", "agreement"]


def test_assert_helper_refuses_an_uncovered_run(variant_llvm_rgb):
    from phonglab.testing import assert_integrator_valid

    args = dict(plugins=[DEFECTS / "direct_double_count_undeclared.py"], quick=True,
                topics=["agreement"])
    with pytest.raises(AssertionError, match="not covered: agreement"):
        assert_integrator_valid("defect_direct_double_count_undeclared", **args)
    report = assert_integrator_valid("defect_direct_double_count_undeclared",
                                     allow_uncovered=True, **args)
    assert report.not_covered == ["agreement"]
