"""The emitter validator: Mitsuba's built-in emitters pass (the sphere finding KNOWN by its
signature), each planted defect fails its own topic and no other, the controls pass, and the
command line detects an emitter.

Quick sizes and seed 0; the statistical rows (chi2 per reference point, the power estimate)
run at the family-wise level ALPHA = 0.01 per emitter (Šidák), so a correct emitter fails a
run with probability ≤ 1 %; the defects are off by far more (a factor π in power, a 1/r law,
a density in the wrong measure).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from phonglab.validate.emitter.topics import TOPICS

from helpers import fails_in_one_sentence, run_cli

DEFECTS = Path(__file__).parent / "defects_emitter"
REPRO = Path(__file__).parent / "repro"
SRC = Path(__file__).parents[1] / "src"

#: defect file -> the topics it must fail (empty: a control)
PLANTED = {
    "point_control": set(),
    "point_inverse_r": {"power"},
    "area_control": set(),
    "area_pdf_measure": {"chi2"},
    "area_ray_missing_pi": {"power"},
    "area_nan_edge": {"finite"},
    "area_weight_noise": {"weight"},
    "area_stale_pdf": {"pdf"},
    "area_wrong_gradient": {"gradient"},
}

#: built-in cases expected to pass at --quick (see validate/emitter/builtins.py)
PASSING = ["point", "spot", "directional", "area (rectangle)", "area (disk)", "area (cube)",
           "area (cylinder)", "area (sphere)", "area (sphere, flip_normals)", "constant", "envmap"]


@pytest.fixture
def builtin_cases(variant_llvm_rgb, tmp_path):
    from phonglab.validate.emitter import builtins

    return builtins.cases(builtins.envmap_file(tmp_path / "env.exr"))


@pytest.mark.parametrize("name", sorted(PLANTED))
def test_defect_fails_its_topic_only(variant_llvm_rgb, name):
    from phonglab.validate import validate_emitter

    report = validate_emitter(f"defect_{name}", plugins=[DEFECTS / f"{name}.py"], quick=True)
    assert {r.topic for r in report.failing} == PLANTED[name], report.table(report.failing)
    assert {r.topic for r in report.rows} == set(TOPICS)


def test_every_topic_but_cost_has_a_planted_defect():
    assert set().union(*PLANTED.values()) | {"cost"} == set(TOPICS)


@pytest.mark.parametrize("label", PASSING)
def test_builtin_emitters_pass_quick(builtin_cases, label):
    from phonglab.validate import validate_emitter

    spec, shape, known = builtin_cases[label]
    report = validate_emitter(spec, shape=shape, known=known, quick=True)
    assert report.passed, report.table(report.failing)


def test_sphere_inside_finding_is_a_failing_pdf_row_without_its_signature(builtin_cases):
    from phonglab.validate import validate_emitter

    spec, shape, known = builtin_cases["area (sphere, flip_normals)"]
    plain = validate_emitter(spec, shape=shape, quick=True, topics=["pdf"])
    assert [r.name for r in plain.failing] == ["ds.pdf = pdf_direction(ds)"]
    marked = validate_emitter(spec, shape=shape, quick=True, topics=["pdf"], known=known)
    assert marked.passed and marked.rows[0].status == "KNOWN"
    assert marked.rows[0].details["known_by"] == ["sphere_emitter_inside"]


def test_signature_does_not_cover_points_off_the_surface(variant_llvm_rgb):
    import numpy as np

    from phonglab.validate.emitter.signatures import SphereSurfaceBand
    from phonglab.validate.emitter.topics import Row

    row = Row("pdf", "ds.pdf = pdf_direction(ds)", 1.0, 0.0, None, 1.0, "fail", "", {})
    row.failing_lanes = {"rel_radius": np.array([1e-7, -0.5])}
    assert SphereSurfaceBand().covers(row).tolist() == [True, False]


def test_sphere_reproducer_exits_1_while_present():
    proc = subprocess.run([sys.executable, str(REPRO / "sphere_emitter_inside.py")],
                          capture_output=True, text=True, env={"PYTHONPATH": str(SRC),
                                                               "PATH": "/usr/bin:/bin"})
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert "ds.pdf != pdf_direction" in proc.stdout


SUN_RIM_ROWS = {"weight x ds.pdf = eval_direction(ds)": "sunsky-sun-rim-weight",
                "weight x ds.pdf = eval at the traced point": "sunsky-sun-rim-weight",
                "ds.pdf = pdf_direction(ds)": "sunsky-sun-rim-pdf"}


def test_sunsky_equator_rows_are_known_by_the_sun_rim_and_a_lane_off_it_stays_a_fail(
        variant_llvm_rgb):
    """At latitude 0, sun samples drawn on the sun cone's rim round 1-2 float32 steps outside
    hit_sun's test (sunsky.h:430/946): the three rows they fail are KNOWN by the finding, each
    failing lane inside its signature (within 4 steps of the rim); a lane planted 5 steps
    outside or inside the cone keeps the row a fail."""
    import numpy as np

    from phonglab.validate import validate_emitter
    from phonglab.validate.known import mark_known
    from phonglab.validate.emitter import builtins

    case = next(c for c in builtins.catalogue_cases() if c.label == "sunsky (equator)")
    report = validate_emitter(case.spec, known=case.known, quick=True, topics=["weight", "pdf"])
    assert report.passed, report.table(report.rows)
    rows = {r.name: r for r in report.rows}
    for name, key in SUN_RIM_ROWS.items():
        row = rows[name]
        assert row.status == "KNOWN" and row.details["known_by"] == [key], name
        steps = row.failing_lanes["sun_rim_ulps"]
        assert len(steps) and np.all(np.abs(steps) <= 4) and np.any(steps < 0), (name, steps)
    for planted in (-5.0, 5.0):
        row = rows["ds.pdf = pdf_direction(ds)"]
        row.status = "fail"
        row.failing_lanes = {k: np.append(v, v[:1], axis=0) for k, v in row.failing_lanes.items()}
        row.failing_lanes["sun_rim_ulps"][-1] = planted
        mark_known([row], case.known)
        assert row.status == "fail" and row.details["outside_signature"]["lanes"] == 1, planted
        row.failing_lanes = {k: v[:-1] for k, v in row.failing_lanes.items()}


def test_sun_rim_signature_covers_a_few_steps_about_the_rim_only():
    import numpy as np

    from phonglab.validate.emitter.signatures import SunConeRim
    from phonglab.validate.emitter.topics import Row

    row = Row("pdf", "ds.pdf = pdf_direction(ds)", 1.0, 0.0, None, 1.0, "fail", "", {})
    row.failing_lanes = {"sun_rim_ulps": np.array([-1.0, -4.0, -5.0, 0.0, 2.0, 4.0, 5.0])}
    assert SunConeRim().covers(row).tolist() == [True, True, False, True, True, True, False]
    row.failing_lanes = {"u": np.zeros((2, 2))}                   # no sun recorded: no claim
    assert SunConeRim().covers(row) is None


def test_sunsky_sun_rim_reproducer_exits_1_while_present():
    proc = subprocess.run([sys.executable, str(REPRO / "sunsky_sun_rim_pdf.py")],
                          capture_output=True, text=True, env={"PYTHONPATH": str(SRC),
                                                               "PATH": "/usr/bin:/bin"})
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert "behaviour present" in proc.stdout


def test_sunsky_without_sky_fails_chi2_by_the_suns_float32_cone_only_there(variant_llvm_rgb):
    """With the sky off the sun holds every sample, and its pdf_direction integrates to
    1.0052 (sunsky.h:946's float32 cone test): χ² rejects it at 10⁶ samples, KNOWN by
    sunsky-sun-pdf-normalization; the same finding explains nothing with the sky on (its
    ``at``: sky_scale ≤ 1e-3), and without the finding the row is a plain fail."""
    from phonglab.validate import validate_emitter
    from phonglab.validate.emitter.kind import known_for

    known = known_for("sunsky", {})
    dark = validate_emitter("sunsky", params={"sky_scale": 0.0}, topics=["chi2"], known=known)
    (row,) = dark.rows
    assert row.status == "KNOWN" and row.details["known_by"] == ["sunsky-sun-pdf-normalization"]
    plain = validate_emitter("sunsky", params={"sky_scale": 0.0}, topics=["chi2"])
    assert [r.status for r in plain.rows] == ["fail"]
    (finding,) = [k for k in known["chi2"] if getattr(k, "key", "") ==
                  "sunsky-sun-pdf-normalization"]
    assert finding.holds_at({"sky_scale": 0.0}) and not finding.holds_at({"sky_scale": 1.0})


def test_cli_detects_an_emitter(tmp_path):
    out = tmp_path / "point.json"
    rc, stdout, stderr = run_cli(["validate", "point", "--quick", "--json", out, "--report",
                                  tmp_path / "p.html", "--variant", "llvm_ad_rgb"])
    assert rc == 0, stdout + stderr
    import json

    data = json.loads(out.read_text())
    assert data["meta"]["emitter"] == "point"
    assert {r["topic"] for r in data["results"]} == set(TOPICS)
    assert "phonglab validate: emitter point" in (tmp_path / "p.html").read_text()


def test_cli_runs_a_defect_plugin_and_fails_it():
    rc, stdout, stderr = run_cli(["validate", "defect_point_inverse_r", "--plugin",
                                  DEFECTS / "point_inverse_r.py", "--quick", "--only", "power",
                                  "--variant", "llvm_ad_rgb"])
    assert rc == 1, stdout + stderr
    assert "intensity law" in stdout


def test_unknown_emitter_topic_is_bad_input(capsys):
    fails_in_one_sentence(capsys, ["validate", "point", "--only", "energy", "--variant",
                                   "llvm_ad_rgb"], "unknown topic 'energy'")


@pytest.fixture
def variant_llvm_spectral():
    """llvm_ad_spectral for one test, the variant before it restored afterwards."""
    import mitsuba as mi

    import phonglab

    before = mi.variant()
    yield phonglab.register("llvm_ad_spectral")
    if before:
        phonglab.register(before)


@pytest.mark.parametrize("label", ["point", "area (rectangle)", "area (sphere, flip_normals)",
                                   "constant", "envmap"])
def test_builtin_emitters_pass_quick_spectral(variant_llvm_spectral, tmp_path, label):
    # spectral: sample_ray draws the wavelengths too, radiance.value holds rgb2spec
    # coefficients (a λ² term): the power and gradient topics handle both
    from phonglab.validate.emitter import builtins
    from phonglab.validate import validate_emitter

    spec, shape, known = builtins.cases(builtins.envmap_file(tmp_path / "env.exr"))[label]
    report = validate_emitter(spec, shape=shape, known=known, quick=True)
    assert report.meta["variant"] == "llvm_ad_spectral"
    assert report.passed, report.table(report.failing)


def test_assert_emitter_valid_names_the_failing_rows(variant_llvm_rgb):
    from phonglab.testing import assert_emitter_valid

    assert_emitter_valid("defect_point_control", plugins=[DEFECTS / "point_control.py"],
                         quick=True, topics=["power"])
    with pytest.raises(AssertionError, match="intensity law"):
        assert_emitter_valid("defect_point_inverse_r", plugins=[DEFECTS / "point_inverse_r.py"],
                             quick=True, topics=["power"])


def test_a_builtin_emitter_carries_the_findings_of_its_shape(capsys):
    """`phonglab validate area` on an inside-out sphere exits 0 though its pdf row fails by the
    documented sphere-emitter finding (sphere.cpp:256): the findings of the catalogue's cases of
    the same shape apply by default (never the sphere's to a rectangle), --no-known shows the raw
    fail."""
    from phonglab.cli import main
    from phonglab.validate.emitter.kind import known_for

    args = ["validate", "area", "--set", "shape.type=sphere", "--set", "shape.flip_normals=true",
            "--quick", "--only", "pdf"]
    assert main(args) == 0
    assert "docs/conformance-emitters.md" in capsys.readouterr().out
    assert main(args + ["--no-known"]) == 1
    assert known_for("area") == {}                                  # the rectangle
    assert known_for("area", {"shape": {"type": "obj", "filename": "m.obj",
                                        "face_normals": True}}) == {}
    assert set(known_for("area", {"shape": {"type": "obj", "filename": "m.obj"}})) == {"chi2"}
