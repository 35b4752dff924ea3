"""The parameter sweep of ``phonglab validate`` (#29): a plugin, not one parameter point.

The planted defects of tests/defects/sweep fire only at a parameter edge: a lobe-selection
weight k_s/(k_d + k_s) that is 0/0 at k_d = k_s = 0, and a pdf normalization wrong only for
exponents below 1.  Each must pass at its given point, fail at the points where it fires and
pass at every other point; the sweep keeps α per plugin (Šidák across points).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from phonglab.cli import main
from phonglab.testing import assert_bsdf_valid
from phonglab.validate import validate_bsdf
from phonglab.validate.bsdf.ranges import BUILTIN, Range
from phonglab.validate.sweep import Point, points
from phonglab.verdict import Report, Row, point_label, table_by_point

SWEEP_DEFECTS = Path(__file__).parent / "defects" / "sweep"


class _P:
    def __init__(self, name, value, rng):
        self.name, self.value, self.range, self.source = name, value, rng, "declared"


def test_points_vary_one_parameter_at_a_time_plus_two_corners():
    params = [_P("a", 0.5, Range(0.0, 1.0)), _P("p", 30.0, Range(0.0, 1e4, (1.0,)))]
    quick = points(params, quick=True)
    assert [pt.params for pt in quick] == [{}, {"a": 0.0}, {"a": 1.0}, {"p": 0.0}, {"p": 1e4},
                                           {"a": 0.0, "p": 0.0}, {"a": 1.0, "p": 1e4}]
    full = [pt.params for pt in points(params)]
    assert {"a": 1e-4} in full and {"p": 1.0} in full and {"p": 5000.0} in full
    assert {"a": 0.5} not in full                       # the given value is not repeated
    assert len(full) == len({tuple(sorted(p.items())) for p in full})


def test_a_point_label_names_its_parameters():
    assert Point({}).label == "given"
    assert point_label({"kd": 0.0, "exponent": 1e4}) == "kd=0, exponent=10000"


@pytest.mark.parametrize("name,firing", [
    ("lobe_weight_nan", {"kd": 0.0, "ks": 0.0, "exponent": 0.0}),
    ("small_exponent_norm", None),
])
def test_a_defect_at_a_parameter_edge_fails_there_and_passes_elsewhere(variant_llvm_rgb, name,
                                                                       firing):
    plugin = [SWEEP_DEFECTS / f"{name}.py"]
    given = validate_bsdf(f"defect_{name}", plugins=plugin, quick=True)
    assert given.passed, given.table(given.failing)       # the defaults alone miss it
    report = validate_bsdf(f"defect_{name}", plugins=plugin, quick=True, sweep=True)
    failing = {point_label(r.point) for r in report.failing}
    assert failing, "the sweep must find the defect"
    if firing is not None:
        assert failing == {point_label(firing)}
    else:                                                 # exponent < 1 only
        assert all(r.point.get("exponent", 20.0) < 1.0 for r in report.failing)
    passing = {point_label(r.point) for r in report.rows} - failing
    assert "given" in passing and len(passing) >= 3


def test_the_sweep_keeps_alpha_per_plugin(variant_llvm_rgb):
    one = validate_bsdf("lambert", quick=True, topics=["chi2"])
    swept = validate_bsdf("lambert", quick=True, topics=["chi2"], sweep=True)
    runs = swept.meta["sweep"]["points"]
    assert runs >= 3
    levels = {r.details["level"] for r in swept.rows}
    assert len(levels) == 1
    m = one.meta["statistical_tests"]
    assert levels.pop() == pytest.approx(1 - (1 - 0.01) ** (1 / (runs * m)))   # Šidák, P·m


def test_set_pins_a_parameter(variant_llvm_rgb):
    report = validate_bsdf("phong", params={"exponent": 3.0}, quick=True, topics=["finite"],
                           sweep=True)
    assert "exponent" not in {p["name"] for p in report.meta["sweep"]["parameters"]}
    assert report.meta["sweep"]["pinned"] == ["exponent"]
    assert all("exponent" not in r.point for r in report.rows)


def test_points_outside_the_range_are_refused_not_failed(variant_llvm_rgb):
    report = validate_bsdf("phong", quick=True, topics=["finite"], sweep=True)
    refused = [r for r in report.meta["sweep"]["runs"] if r["status"] == "refused"]
    assert {"diffuse_reflectance": 1.0} in [r["point"] for r in refused]   # k_d + k_s > 1
    assert all("MaterialError" in r["reason"] for r in refused)
    assert report.passed


def test_builtins_sweep_their_documented_ranges(variant_llvm_rgb):
    report = validate_bsdf("roughconductor", params={"material": "Au"}, quick=True,
                           topics=["finite"], sweep=True)
    swept = {p["name"]: p for p in report.meta["sweep"]["parameters"]}
    assert set(swept) == set(BUILTIN["roughconductor"])
    assert swept["alpha"]["source"] == "mitsuba" and swept["alpha"]["lo"] == 0.01


def test_an_undeclared_plugin_is_probed(variant_llvm_rgb):
    defects = Path(__file__).parent / "defects"
    report = validate_bsdf("defect_weight_noise", plugins=[defects / "weight_noise.py"],
                           quick=True, topics=["finite"], sweep=True)
    (p,) = report.meta["sweep"]["parameters"]
    assert p["name"] == "reflectance" and p["source"] == "probed" and p["lo"] == 0.0


def test_json_rows_carry_their_point_and_a_single_point_run_has_none(variant_llvm_rgb,
                                                                    tmp_path, capsys):
    out = tmp_path / "r.json"
    assert main(["validate", "lambert", "--quick", "--only", "finite", "--json",
                 str(out)]) == 0
    rows = json.loads(out.read_text())["results"]
    assert {json.dumps(r["point"], sort_keys=True) for r in rows} >= {"{}",
                                                                      '{"reflectance": 0.0}'}
    assert "swept" in capsys.readouterr().out
    assert main(["validate", "lambert", "--quick", "--only", "finite", "--no-sweep", "--json",
                 str(out)]) == 0
    assert all("point" not in r for r in json.loads(out.read_text())["results"])
    back = Report.from_dict(json.loads(out.read_text()))
    assert all(r.point is None for r in back.rows)


def test_the_table_groups_by_point_and_shows_the_worst():
    rows = [Row("finite", "a", 0.0, 0.0, None, 0.0, "pass", "", {}, point={}),
            Row("finite", "a", 5.0, 0.0, None, 0.0, "fail", "bad", {}, point={"k": 0.0})]
    text = table_by_point(rows)
    assert "given" in text and "all pass" in text
    assert "fail finite: a (5 against 0)" in text and "at k=0:" in text


def test_assert_bsdf_valid_sweeps_and_names_the_point(variant_llvm_rgb):
    with pytest.raises(AssertionError, match=r"at kd=0, ks=0, exponent=0:"):
        assert_bsdf_valid("defect_lobe_weight_nan",
                          plugins=[SWEEP_DEFECTS / "lobe_weight_nan.py"], quick=True,
                          topics=["finite"])


def test_an_emitter_is_swept_over_its_documented_range(variant_llvm_rgb):
    """The sweep is every kind's (#35): a built-in emitter across its emitted quantity, from 0
    (where the identity topics' ratios are 0/0 and the gradient's sampling factor is undefined:
    skipped there, saying why) to 10; a correct emitter passes at every point."""
    from phonglab.validate import validate_emitter

    report = validate_emitter("point", quick=True, sweep=True)
    sw = report.meta["sweep"]
    assert [(p["name"], p["lo"], p["hi"], p["source"]) for p in sw["parameters"]] == \
        [("intensity", 0.0, 10.0, "mitsuba")]
    assert {tuple(sorted(r.point.items())) for r in report.rows} == \
        {(), (("intensity", 0.0),), (("intensity", 10.0),)}
    assert report.passed, report.table(report.failing)
    dark = [r for r in report.rows if r.topic == "gradient" and r.point == {"intensity": 0.0}]
    assert dark and dark[0].status == "skipped" and "no radiance arrives" in dark[0].reason


def test_a_dark_surface_emitter_is_still_chi2_tested(variant_llvm_rgb):
    """At radiance 0 every weight is 0: the χ² counts samples where pdf_direction > 0 (it
    failed with 'no sample has a non-zero weight'), and the one-sided back stays untested."""
    from phonglab.validate import validate_emitter

    report = validate_emitter("area", params={"radiance": 0.0}, quick=True, topics=["chi2"])
    (row,) = report.rows
    assert row.status == "pass", row.reason
    assert all(p.get("dark") or p["status"] == "empty" for p in row.details["points"])
