"""The parameter sweep of ``phonglab validate``: a plugin, not one parameter point.

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


def test_an_undeclared_parameter_named_as_mitsuba_names_it_carries_that_domain(variant_llvm_rgb):
    defects = Path(__file__).parent / "defects"
    report = validate_bsdf("defect_weight_noise", plugins=[defects / "weight_noise.py"],
                           quick=True, topics=["finite"], sweep=True)
    (p,) = report.meta["sweep"]["parameters"]
    assert (p["name"], p["source"], p["lo"], p["hi"]) == ("reflectance", "named", 0.0, 1.0)


def test_a_bright_lambert_without_declared_ranges_fails_energy_at_reflectance_1(
        variant_llvm_rgb, tmp_path):
    """3 % too bright at reflectance 1 fails: ``reflectance`` carries Mitsuba's [0, 1] and the
    bound is judged there (a probed range, no domain, would give an advice row only)."""
    text = (Path(__file__).parent / "authors" / "my_lambert.py").read_text()
    bright = tmp_path / "bright.py"
    bright.write_text(text.replace("self.reflectance * dr.inv_pi", "self.reflectance * 1.03 * dr.inv_pi")
                      .replace('"my_lambert"', '"bright_lambert"'))
    report = validate_bsdf("bright_lambert", plugins=[bright], quick=True, topics=["energy"],
                           sweep=True)
    failing = [r for r in report.rows if r.status == "fail"]
    assert [r.point for r in failing] == [{"reflectance": 1.0}], report.table()
    assert not report.meta["sweep"]["advice"]


def test_an_undeclared_parameter_of_no_mitsuba_name_is_probed(variant_llvm_rgb, tmp_path):
    text = (Path(__file__).parent / "authors" / "my_lambert.py").read_text()
    kd = tmp_path / "kd.py"
    kd.write_text(text.replace('props.get("reflectance", 0.5)', 'props.get("kd", 0.5)')
                  .replace('callback.put("reflectance"', 'callback.put("kd"')
                  .replace('"my_lambert"', '"kd_lambert"'))
    report = validate_bsdf("kd_lambert", plugins=[kd], quick=True, topics=["finite"], sweep=True)
    (p,) = report.meta["sweep"]["parameters"]
    assert p["name"] == "kd" and p["source"] == "probed" and p["lo"] == 0.0


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
    assert "fail finite: a (measured 5, expected 0 (tolerance 0))" in text and "at k=0:" in text


def test_assert_bsdf_valid_sweeps_and_names_the_point(variant_llvm_rgb):
    with pytest.raises(AssertionError, match=r"at kd=0, ks=0, exponent=0:"):
        assert_bsdf_valid("defect_lobe_weight_nan",
                          plugins=[SWEEP_DEFECTS / "lobe_weight_nan.py"], quick=True,
                          topics=["finite"])


def test_an_emitter_is_swept_over_its_documented_range(variant_llvm_rgb):
    """The sweep is every kind's: a built-in emitter across its emitted quantity, from 0
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


def test_an_energy_excess_outside_the_domain_is_advice_not_a_fail(variant_llvm_rgb, tmp_path,
                                                                  capsys):
    """A correct author-style Lambert whose plain-float kd is accepted up to 10⁴
    (probed, no PARAMETER_RANGES) passes, the albedo 10⁴ at kd = 10⁴ being advice shown in the
    text, the JSON and the HTML report."""
    out, page = tmp_path / "r.json", tmp_path / "r.html"
    rc = main(["validate", "author_lambert", "--plugin", str(SWEEP_DEFECTS / "plain_lambert.py"),
               "--quick", "--only", "energy", "--json", str(out), "--report", str(page)])
    text = capsys.readouterr().out
    assert rc == 0, text
    assert "accepts kd = 10000, where the directional albedo is 1e+04" in text
    assert "declare PARAMETER_RANGES or refuse it" in text
    d = json.loads(out.read_text())
    (row,) = [r for r in d["results"] if r["status"] == "advice"]
    assert row["topic"] == "energy" and row["point"] == {"kd": 10000.0}
    (advice,) = d["meta"]["sweep"]["advice"]
    assert advice["parameter"] == "kd" and advice["starts_at"] == 10000.0
    assert advice["measured"] == pytest.approx(1e4, rel=1e-3)
    html = page.read_text()
    assert "advice" in html and "accepts kd = 10000" in html


def test_an_energy_defect_inside_the_domain_still_fails(variant_llvm_rgb):
    """The planted gain (albedo 1.5 kd) fails at the given point kd = 0.8 (albedo 1.2): the
    domain rule never turns a fail at the given point into advice."""
    report = validate_bsdf("author_lambert_gain", plugins=[SWEEP_DEFECTS / "plain_lambert.py"],
                           quick=True, topics=["energy"], sweep=True)
    failing = [r for r in report.failing if r.topic == "energy"]
    assert [r.point for r in failing] == [{}], report.table()
    assert failing[0].measured == pytest.approx(1.2, rel=1e-3)
    assert any(r.status == "advice" for r in report.rows)    # kd = 10⁴ is still advice


def test_a_declared_domain_keeps_the_bound_a_fail():
    """A bound row at a point of declared/documented parameters stays a fail; a probed one
    becomes advice; an identity row never does."""
    from phonglab.validate.sweep import advise

    swept = [_P("kd", 0.5, Range(0.0, 1.0))]
    probed = _P("ks", 0.5, Range(0.0, 1e4))
    probed.source = "probed"
    rows = [Row("energy", "directional albedo ≤ 1", 1.3, 1.0, None, 0.01, "fail", "r",
                {"relation": "<="}, point={"kd": 1.0}),
            Row("energy", "directional albedo ≤ 1", 50.0, 1.0, None, 0.01, "fail", "r",
                {"relation": "<="}, point={"ks": 100.0}),
            Row("weight", "weight = eval/pdf", 9.0, 0.0, None, 1.0, "fail", "r", {},
                point={"ks": 100.0})]
    advice = advise(rows, swept + [probed], ("energy",))
    assert [r.status for r in rows] == ["fail", "advice", "fail"]
    assert advice[0]["text"].startswith("accepts ks = 100, where the directional albedo is 50")


@pytest.mark.parametrize("value", ["-1", "1e30"])
def test_a_set_value_outside_its_documented_range_is_bad_input(variant_llvm_rgb, capsys, value):
    """--set alpha=-1 or 1e30 is exit 2 in one sentence naming the range and where it comes
    from, before any topic runs (not a 23 s run of failing rows)."""
    import time
    t0 = time.perf_counter()
    assert main(["validate", "roughplastic", "--set", f"alpha={value}"]) == 2
    assert time.perf_counter() - t0 < 5.0
    err = capsys.readouterr().err
    assert "outside the range [0.01, 1] of roughplastic's alpha" in err
    assert "Mitsuba 3.9.1's plugin reference" in err and "Traceback" not in err


def test_a_set_value_outside_a_declared_range_is_bad_input(variant_llvm_rgb, capsys):
    assert main(["validate", "phong", "--set", "exponent=2e4", "--no-sweep"]) == 2
    assert "declared by the plugin class's PARAMETER_RANGES" in capsys.readouterr().err


def test_an_emitters_sweep_extent_is_no_limit_on_set(variant_llvm_rgb):
    """The emitted quantity's [0, 10] is where the sweep goes, not a documented limit: a
    20 W/sr point light is validated, not refused."""
    assert main(["validate", "point", "--set", "intensity=20", "--no-sweep", "--only",
                 "finite"]) == 0


def test_a_count_is_swept_over_whole_numbers_up_to_its_sweep_extent():
    """An integrator's rr_depth is valid from 1 up (unbounded): the sweep tries whole numbers,
    the ends and the middle of [1, 64], and --set is held to [1, ∞)."""
    from phonglab.validate.integrator.ranges import BUILTIN as INTEGRATORS
    rr = INTEGRATORS["path"]["rr_depth"]
    assert rr.values() == (1, 32, 64) and all(type(v) is int for v in rr.values())
    assert rr.values(quick=True) == (1, 64)
    assert rr.lo == 1 and rr.hi == float("inf")
    corners = points([_P("rr_depth", 5, rr), _P("emitter_samples", 1, Range(1, 9, integer=True,
                                                                            sweep_hi=4))])
    assert Point({"rr_depth": 64, "emitter_samples": 4}) in corners


def test_an_integrators_estimator_controls_are_swept_and_direct_is_pinned(variant_llvm_rgb):
    """The sweep is every kind's.  direct's emitter_samples and bsdf_samples run 1..4;
    at emitter_samples 4 the plane under a point light reads 4x the exact value (Mitsuba
    3.9.1's direct.cpp:180 sums a delta light's emitter samples; mitsuba3 #1861): KNOWN by the
    table's finding there, a pass at the given point and wherever emitter_samples is 1."""
    from phonglab.validate import validate_integrator
    from phonglab.validate.registry import by_name

    known = by_name("integrator").part("known_for")("direct", None)
    report = validate_integrator("direct", quick=True, topics=["bias"], known=known,
                                 sweep=True)
    sw = report.meta["sweep"]
    assert [(p["name"], p["lo"], p["hi"], p["source"]) for p in sw["parameters"]] == \
        [("emitter_samples", 1, 4, "mitsuba"), ("bsdf_samples", 1, 4, "mitsuba")]
    plane = {tuple(sorted(r.point.items())): r for r in report.rows
             if r.name == "plane under a point light"}
    assert plane[()].status == "pass" and plane[(("emitter_samples", 1),)].status == "pass"
    four = plane[(("emitter_samples", 4),)]
    assert four.status == "KNOWN", four.reason
    assert four.details["known_by"] == ["direct-delta-emitter-samples"]
    assert four.measured == pytest.approx(4 * plane[()].expected, rel=0.01)
    assert report.passed


def test_hg_is_swept_over_g_and_an_undeclared_python_phase_function_is_not_probed(
        variant_llvm_rgb):
    """hg's g runs over [-0.99, 0.99] (±0.99 at --quick) and passes; a Python phase function
    with a plain-float g and no PARAMETER_RANGES is checked at its given point, and the report
    says how to sweep it (a probe would load g = 10, where no formula is a density)."""
    from phonglab.validate import validate_phase

    report = validate_phase("hg", quick=True, topics=["finite", "chi2", "normalization"],
                            sweep=True)
    assert {tuple(sorted(r.point.items())) for r in report.rows} == \
        {(), (("g", -0.99),), (("g", 0.99),)}
    assert report.passed, report.table(report.failing)
    mine = validate_phase("defect_hg_control", quick=True, topics=["finite"], sweep=True,
                          plugins=[Path(__file__).parent / "defects_phase" / "hg_control.py"])
    assert mine.meta["sweep"]["points"] == 1 and mine.meta["sweep"]["parameters"] == []
    assert "declare PARAMETER_RANGES" in mine.meta["sweep"]["note"]


@pytest.mark.parametrize("args, message", [
    (["point", "--set", "intensity=-1"], "outside the range [0, inf] of point's intensity"),
    (["direct", "--set", "emitter_samples=0"],
     "outside the range [1, inf] of direct's emitter_samples"),
    (["hg", "--set", "g=-0.995"], "outside the range [-0.99, 0.99] of hg's g"),
])
def test_a_set_outside_the_domain_is_bad_input_for_every_kind(variant_llvm_rgb, capsys, args,
                                                               message):
    assert main(["validate", *args]) == 2
    err = capsys.readouterr().err
    assert message in err and "phonglab.validate." in err and "Traceback" not in err


def test_an_identity_of_a_bound_topic_fails_at_every_point_never_advice(variant_llvm_rgb):
    """A point light falling off as I/r breaks the inverse-square law at every intensity; it
    was advice ("a physical bound exceeded outside the declared domain") at intensity 10⁴."""
    from phonglab.validate import validate_emitter
    plugin = Path(__file__).parent / "defects_emitter" / "point_inverse_r.py"
    report = validate_emitter("defect_point_inverse_r", plugins=[plugin], quick=True,
                              topics=["power"], sweep=True)
    law = [r for r in report.rows if r.name.startswith("intensity law")
           and (r.point or {}).get("intensity", 1.0) > 0]          # I = 0: 0 = 0 holds
    assert len(law) >= 2 and all(r.status == "fail" for r in law)
    assert any((r.point or {}).get("intensity") == 10000 for r in law)
    assert not report.meta["sweep"]["advice"]
