"""KNOWN by signature: a documented cause explains the failing lanes it names, never a topic.

A failing row becomes KNOWN only when every failing lane lies in the signature (rows and input
region) of a cause that names it; a lane outside keeps the row a fail, with the count and the
first such lane in its details.  The planted defects of tests/defects give failures whose
lanes are known exactly (NaN at cos θ_i = 0; a sampler off in the upper hemisphere; swapped
component indices), so each signature can be held against lanes inside and outside it.
"""

from __future__ import annotations

from pathlib import Path

import mitsuba as mi
import numpy as np
import pytest

from phonglab.validate import validate_bsdf
from phonglab.validate.bsdf.findings import FINDINGS
from phonglab.validate.bsdf.signatures import (BelowHorizon, Chi2Outside, ComponentOfAnotherLobe,
                                               ComponentOutOfRange, GrazingIncidence, SamplePoint,
                                               bin_mask)
from phonglab.validate.known import Known, mark_known
from phonglab.verdict import Row

DEFECTS = Path(__file__).parent / "defects"
CAUSE = "src/x.cpp:1: a documented cause"
NAN_ROWS = ("eval: NaN/Inf/negative values", "eval_pdf: NaN/Inf/negative values")


def _failing_row(wi):
    row = Row("finite", "eval: NaN/Inf/negative values", 2.0, 0.0, None, 0.0, "fail", "why", {})
    row.failing_lanes = {"wi": np.asarray(wi, float), "wo": np.zeros((len(wi), 3))}
    return row


def test_a_lane_outside_the_signature_keeps_the_row_a_fail():
    row = _failing_row([[1.0, 0.0, 0.0], [0.6, 0.0, 0.8]])         # grazing, and not
    mark_known([row], {"finite": Known(CAUSE, NAN_ROWS[:1], GrazingIncidence(), "k")})
    assert row.status == "fail"
    assert row.details["outside_signature"]["lanes"] == 1
    assert row.details["outside_signature"]["first"]["wi"] == [0.6, 0.0, 0.8]
    assert "1 of 2 failing lanes lie outside every documented signature" in row.reason


def test_every_lane_inside_makes_it_known_and_names_the_finding():
    row = _failing_row([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    mark_known([row], {"finite": Known(CAUSE, NAN_ROWS[:1], GrazingIncidence(), "k")})
    assert row.status == "KNOWN" and row.reason.startswith(CAUSE)
    assert row.details["known_by"] == ["k"]


def test_a_cause_explains_only_the_rows_it_names():
    row = _failing_row([[1.0, 0.0, 0.0]])
    mark_known([row], {"finite": Known(CAUSE, ("pdf: NaN/Inf/negative values",),
                                       GrazingIncidence())})
    assert row.status == "fail"


def test_a_region_the_row_cannot_be_checked_against_covers_nothing():
    row = _failing_row([[1.0, 0.0, 0.0]])                # no sample2 recorded
    mark_known([row], {"finite": Known(CAUSE, NAN_ROWS[:1], SamplePoint((0.0, 0.5)))})
    assert row.status == "fail"


def test_a_plain_string_is_a_whole_topic_judgement_as_before():
    row = _failing_row([[0.6, 0.0, 0.8]])
    mark_known([row], {"finite": CAUSE})
    assert row.status == "KNOWN"


def test_chi2_outside_confines_the_discrepancy_to_its_bins():
    shape = (101, 50)
    exp = np.full(shape, 200.0)
    below = bin_mask("below_horizon", shape)
    assert below[-1].all() and not below[0].any()       # row 0 is the normal direction
    rng = np.random.default_rng(0)
    obs = rng.poisson(exp).astype(float)
    obs[below] = 0.0                                      # samples never go below the horizon
    cell = {"histogram": obs.tolist(), "expected": exp.tolist()}
    row = Row("chi2", "sampling matches pdf (min p-value)", 0.0, 1e-3, None, 1e-3, "fail", "",
              {"level": 1e-3})
    row.failing_lanes = {"cell": [cell]}
    assert Chi2Outside("below_horizon").covers(row).tolist() == [True]
    obs[3, 7] += 500.0                                    # and a defect above the horizon
    cell["histogram"] = obs.tolist()
    assert Chi2Outside("below_horizon").covers(row).tolist() == [False]


def test_nan_at_exact_grazing_is_known_only_under_the_grazing_signature(variant_llvm_rgb):
    plugin = [DEFECTS / "nan_grazing.py"]
    known = {"finite": Known(CAUSE, NAN_ROWS, GrazingIncidence(), "grazing")}
    report = validate_bsdf("defect_nan_grazing", plugins=plugin, quick=True, topics=["finite"],
                           known=known)
    assert not report.failing and any(r.status == "KNOWN" for r in report.rows)
    report = validate_bsdf("defect_nan_grazing", plugins=plugin, quick=True, topics=["finite"],
                           known={"finite": Known(CAUSE, NAN_ROWS, BelowHorizon())})
    assert not report.failing                            # cos θ_i = 0 is at the horizon
    report = validate_bsdf("defect_nan_grazing", plugins=plugin, quick=True, topics=["finite"],
                           known={"finite": Known(CAUSE, NAN_ROWS[1:], GrazingIncidence())})
    assert [r.name for r in report.failing] == [NAN_ROWS[0]]


def test_a_sampler_wrong_above_the_horizon_hides_behind_no_below_horizon_finding(
        variant_llvm_rgb):
    known = {"chi2": Known(CAUSE, ("sampling matches pdf (min p-value)",),
                           Chi2Outside("below_horizon"), "below")}
    report = validate_bsdf("defect_pdf_mismatch", plugins=[DEFECTS / "pdf_mismatch.py"],
                           quick=True, topics=["chi2"], known=known)
    (row,) = report.failing
    assert row.details["outside_signature"]["findings"] == ["below"]


def test_swapped_component_ids_match_the_numbering_signature_only(variant_llvm_rgb):
    plugin = [DEFECTS / "swapped_components.py"]
    rows = ("sampled_component/sampled_type agree with the flags",
            "restricted context samples only its component")
    report = validate_bsdf("defect_swapped_components", plugins=plugin, quick=True,
                           topics=["component"],
                           known={"component": Known(CAUSE, rows, ComponentOfAnotherLobe())})
    assert {r.name for r in report.rows if r.status == "KNOWN"} >= set(rows[:1])
    report = validate_bsdf("defect_swapped_components", plugins=plugin, quick=True,
                           topics=["component"],
                           known={"component": Known(CAUSE, rows, ComponentOutOfRange())})
    assert rows[0] in {r.name for r in report.failing}


def test_every_finding_has_a_signature():
    for f in FINDINGS:
        assert f.rows, f.key
        k = f.known()
        assert k.key == f.key and k.cause.startswith(f.source)


def test_known_for_plugin_unites_the_causes_of_every_case_of_that_plugin_once():
    """A sweep of a built-in meets the findings of all of its table cases: each cause once,
    and only causes of that plugin's cases (each still matches only its own signature)."""
    from phonglab.validate.bsdf.builtins import cases, known_for_plugin
    known = known_for_plugin("roughplastic")
    for topic in {t for case in cases() if case.plugin == "roughplastic" for t in case.known}:
        expected = [c for case in cases() if case.plugin == "roughplastic"
                    for c in case.known.get(topic, ())]
        assert len(known[topic]) == len(set(known[topic])) == len(set(expected))
        assert set(known[topic]) == set(expected)
    assert "gradient" in known and "finite" in known      # the detached alpha, the 0/0 when black
    assert known_for_plugin("no-such-plugin") == {}


def test_a_cause_at_a_parameter_interval_holds_inside_it_only():
    """plastic's F_dr-fit energy gain is documented for int_ior in [2, 3]: a failing energy
    row at int_ior 1.49 is not explained by it."""
    cause = Known("fit", rows=("directional albedo ≤ 1",), at=(("int_ior", (2.0, 3.0)),))
    assert cause.holds_at({"int_ior": 3.0}) and cause.holds_at({"int_ior": 2.0})
    assert not cause.holds_at({"int_ior": 1.49}) and not cause.holds_at({})
    assert "int_ior in [2, 3]" in cause.describe()


def test_principled_sweep_findings_hold_only_at_their_points():
    """The principled findings of the sweep explain their points and no others: the
    shifted component numbering needs spec_trans on and clearcoat off, the by-design energy
    gains a white base_color or roughness 0.1, the metal's diffuse reflectance metallic 1
    and specular 0, principledthin's grazing NaN and transmission asymmetry spec_trans > 0."""
    by_key = {f.key: f.known() for f in FINDINGS}
    shifted = by_key["principled-component-ids-shifted"]
    assert shifted.holds_at({"spec_trans": 1.0, "clearcoat": 0.0})
    assert not shifted.holds_at({"spec_trans": 1.0, "clearcoat": 1.0})
    assert not shifted.holds_at({"spec_trans": 0.0, "clearcoat": 0.0})
    for key in ("principledthin-pdf-nan-grazing", "principledthin-transmission-reciprocity"):
        assert by_key[key].holds_at({"spec_trans": 0.3}) and by_key[key].holds_at({"spec_trans": 1e-4})
        assert not by_key[key].holds_at({"spec_trans": 0.0})
    assert by_key["principled-diffuse-retro-energy"].holds_at({"base_color": 1.0})
    assert not by_key["principled-diffuse-retro-energy"].holds_at({"base_color": 0.5})
    assert not by_key["principled-specular-uncoupled-energy"].holds_at({"roughness": 0.5})
    metal = by_key["principled-metal-diffuse-reflectance"]
    assert metal.holds_at({"metallic": 1.0, "specular": 0.0})
    assert not metal.holds_at({"metallic": 1.0, "specular": 0.5})
    energy = {f.key for f in FINDINGS if f.topic == "energy" and not f.bug}
    assert {"principled-diffuse-retro-energy", "principled-specular-uncoupled-energy"} <= energy


def test_roughdielectric_index_matched_energy_explains_its_signature_only(variant_llvm_rgb):
    """Roughdielectric's energy row fails near eta = 1 (the sweep's corner int_ior 1
    against the default ext_ior, air: eta 0.99972); the finding explains that row at
    eta in [0.998, 1.015] and nothing else: not the same row at eta 1.5 or 0.99, not
    another topic's failing row at eta 0.99972."""
    from phonglab.validate.bsdf.builtins import known_for_plugin
    from phonglab.validate.bsdf.findings import ENERGY_ROW

    key = "roughdielectric-index-matched-energy"
    cause = {f.key: f.known() for f in FINDINGS}[key]
    assert cause.rows == (ENERGY_ROW,)
    for eta in (0.998, 0.99972, 1.0001, 1.015):
        assert cause.holds_at({"eta": eta}), eta
    for eta in (0.99, 0.995, 1.02, 1.5):
        assert not cause.holds_at({"eta": eta}), eta
    assert not cause.holds_at({})
    known = known_for_plugin("roughdielectric")
    assert cause in known["energy"]

    def failing(topic, name):
        return Row(topic, name, 1.01, 1.0, None, 1e-4, "fail", "why", {})
    rows = [failing("energy", ENERGY_ROW), failing("weight", "sample weight = eval / pdf")]
    mark_known(rows, known, {"eta": 0.99972, "alpha": 0.1})
    assert [r.status for r in rows] == ["KNOWN", "fail"]
    assert rows[0].details["known_by"] == [key]
    for eta in (1.5, 0.99):
        row = failing("energy", ENERGY_ROW)
        mark_known([row], known, {"eta": eta, "alpha": 0.1})
        assert row.status == "fail", eta

    # the real row: Beckmann alpha 0.1 at int_ior 1 (eta 0.99972) fails, and is this finding
    spec = {"alpha": 0.1, "int_ior": 1.0}
    plain = validate_bsdf("roughdielectric", params=spec, topics=["energy"], quick=True)
    assert [r.status for r in plain.rows] == ["fail"]
    marked = validate_bsdf("roughdielectric", params=spec, topics=["energy"], known=known,
                           quick=True)
    assert [r.status for r in marked.rows] == ["KNOWN"]
    assert marked.rows[0].details["known_by"] == [key]
    glass = validate_bsdf("roughdielectric", params={"alpha": 0.1, "int_ior": 1.5},
                          topics=["energy"], known=known, quick=True)
    assert [r.status for r in glass.rows] == ["pass"]


def test_roughdielectric_index_matched_normalization_explains_its_signature_only(
        variant_llvm_rgb):
    """Roughdielectric's normalization row fails near eta = 1 for GGX too (int_ior 1
    against air: eta 0.99972; the float32 product wo * eta in pdf()'s half vector); the
    finding explains that row at eta in [0.999, 1.001] and incidence |cos θ_i| ≥ 0.03 only
    (the energy grid's 0.05 is in, 0.01 is out): not at eta 0.998 or 1.5, not a failing
    grazing cell (cos θ_i 0.01, where the product's effect is ≤ 3e-5), not another topic's
    row at eta 0.99972."""
    from phonglab.validate.bsdf.builtins import known_for_plugin
    from phonglab.validate.bsdf.findings import NORM_ROW
    from phonglab.validate.bsdf.signatures import IncidenceFrom

    key = "roughdielectric-index-matched-normalization"
    cause = {f.key: f.known() for f in FINDINGS}[key]
    assert cause.rows == (NORM_ROW,) and cause.region == IncidenceFrom(0.03)
    for eta in (0.999, 0.99972, 0.99982, 1.0003, 1.001):      # 0.99982: int_ior 1.0001
        assert cause.holds_at({"eta": eta}), eta
    for eta in (0.998, 1.002, 1.5):
        assert not cause.holds_at({"eta": eta}), eta
    assert not cause.holds_at({})
    ggx = known_for_plugin("roughdielectric", {"distribution": "ggx"})
    assert cause in ggx["normalization"]
    assert cause in known_for_plugin("roughdielectric")["normalization"]   # Beckmann as well

    def failing(topic, name, cos_theta):
        row = Row(topic, name, 1.0004, 1.0, None, 3e-4, "fail", "why", {})
        s = np.sqrt(1 - cos_theta ** 2)
        row.failing_lanes = {"wi": np.array([[s, 0.0, cos_theta]])}
        return row

    rows = [failing("normalization", NORM_ROW, 0.7), failing("normalization", NORM_ROW, 0.05),
            failing("normalization", NORM_ROW, 0.01),
            failing("weight", "sample weight = eval / pdf", 0.7)]
    mark_known(rows, ggx, {"eta": 0.99972, "alpha": 0.1})
    assert [r.status for r in rows] == ["KNOWN", "KNOWN", "fail", "fail"]
    assert rows[0].details["known_by"] == [key]
    for eta in (1.5, 0.998):
        row = failing("normalization", NORM_ROW, 0.7)
        mark_known([row], ggx, {"eta": eta, "alpha": 0.1})
        assert row.status == "fail", eta

    # the real rows of `validate roughdielectric --set distribution=ggx --quick` at int_ior 1
    # (alpha 0.1 at 45.6 deg, alpha 0.01 at 72.5 deg), on those cells only (0.7 s each); the
    # same cells at int_ior 1.5 pass
    for params, cos, where in (({"int_ior": 1.0}, (1.0, 0.7), "45.6°"),
                               ({"alpha": 0.01, "int_ior": 1.0}, (0.3,), "72.5°"),
                               ({"int_ior": 1.5}, (1.0, 0.7), None)):
        report = validate_bsdf("roughdielectric", params={"distribution": "ggx", **params},
                               topics=["normalization"], known=ggx, quick=True,
                               sizes={"energy_cos": cos})
        (row,) = report.rows
        if where is None:
            assert row.status == "pass", params
            continue
        assert row.status == "KNOWN", params
        assert row.details["known_by"] == [key]
        assert f"NOT NORMALIZED at θ_i = {where}" in row.reason


@pytest.mark.parametrize("variant, sets, topic, key", [
    ("llvm_ad_rgb", ["diffuse_reflectance=0", "specular_reflectance=0"], "finite",
     "pplastic-black-nan-pdf"),
    ("llvm_ad_spectral_polarized", ["int_ior=3", "alpha=1"], "reciprocity",
     "pplastic-polarized-grazing")])
def test_pplastic_sweep_corners_are_known_by_their_findings(tmp_path, variant, sets, topic, key):
    """Two corners of pplastic's sweep fail (--quick), each by its finding: both
    reflectances 0 (the 0/0 sampling weight, pplastic.cpp:239) and int_ior = 3 (the polarized
    grazing cancellation, pplastic.cpp:377, whose band widens with eta to min cos 0.0197).
    Typed on the command line as an author would: an integer int_ior loads (settings.IOR_NAMES),
    and the rows read KNOWN by those findings; with --no-known they are fails."""
    import json

    from phonglab.cli import main
    args = ["validate", "pplastic", "--no-sweep", "--quick", "--only", topic,
            "--variant", variant] + [a for s in sets for a in ("--set", s)]
    out = tmp_path / "r.json"
    assert main(args + ["--json", str(out)]) == 0
    rows = [r for r in json.loads(out.read_text())["results"] if r["status"] == "KNOWN"]
    assert rows and all(key in r["details"]["known_by"] for r in rows)
    assert main(args + ["--no-known"]) == 1
