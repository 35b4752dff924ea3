"""The phase-function validator: Mitsuba's built-in isotropic and hg pass, each planted defect
fails its own topic and no other, the controls pass, the catalogue's failing rows are KNOWN by
their findings' signatures, and the findings' reproducers exit 1.

Quick sizes and seed 0; the χ² rows run at the family-wise level ALPHA = 0.01 per phase
function (Šidák over its incidences), so a correct phase function fails a run with
probability ≤ 1 %; normalization is a deterministic quadrature with its own error bound; the
defects are off by far more (an opposite g, a factor 2π, a weight 2u).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from phonglab.validate.phase.topics import TOPICS

DEFECTS = Path(__file__).parent / "defects_phase"
REPRO = Path(__file__).parent / "repro"
SRC = Path(__file__).parents[1] / "src"

#: defect file -> the topics it must fail (empty: a control)
PLANTED = {
    "hg_control": set(),
    "isotropic_control": set(),
    "hg_opposite_g": {"chi2"},
    "tab_mismatch": {"chi2"},
    "hg_pdf_per_mu": {"normalization"},
    "hg_weight_noise": {"weight"},
    "hg_stale_pdf": {"pdf"},
    "hg_nan_g0": {"finite"},
    "hg_g_from_wi": {"reciprocity"},
    "hg_wrong_gradient": {"gradient"},
}


@pytest.mark.parametrize("name", sorted(PLANTED))
def test_defect_fails_its_topic_only(variant_llvm_rgb, name):
    from phonglab.validate import validate_phase

    report = validate_phase(f"defect_{name}", plugins=[DEFECTS / f"{name}.py"], quick=True)
    assert {r.topic for r in report.failing} == PLANTED[name], report.table(report.failing)
    assert {r.topic for r in report.rows} == set(TOPICS)


def test_every_topic_but_cost_has_a_planted_defect():
    assert set().union(*PLANTED.values()) | {"cost"} == set(TOPICS)


@pytest.mark.parametrize("spec", [{"type": "isotropic"}, {"type": "hg", "g": 0.5}],
                         ids=["isotropic", "hg-0.5"])
def test_builtin_isotropic_and_hg_pass(variant_llvm_rgb, spec):
    from phonglab.validate import validate_phase

    report = validate_phase(spec, quick=True)
    assert report.passed, report.table(report.failing)
    assert not any(r.status == "KNOWN" for r in report.rows)


@pytest.mark.slow
def test_catalogue_passes_with_its_findings(variant_llvm_rgb):
    from phonglab.validate.phase.builtins import CATALOGUE
    from phonglab.validate import validate_phase

    for case in CATALOGUE.cases():
        report = validate_phase(case.spec, quick=True, known=case.known)
        assert report.passed, (case.label, report.table(report.failing))


def test_sggx_findings_are_known_by_signature(variant_llvm_rgb):
    from phonglab.validate.phase.builtins import CATALOGUE
    from phonglab.validate import validate_phase

    case = CATALOGUE.find("sggx (0.15, 1, 0.8)")
    plain = validate_phase(case.spec, quick=True, topics=["finite", "chi2"])
    assert {r.topic for r in plain.failing} == {"finite", "chi2"}
    marked = validate_phase(case.spec, quick=True, topics=["finite", "chi2"], known=case.known)
    assert marked.passed
    assert {k for r in marked.rows for k in r.details.get("known_by", [])} == {
        "sggx-eval-forward-nan", "sggx-sample-frame-transposed"}


def test_hg_small_g_finding_holds_only_near_zero(variant_llvm_rgb):
    from phonglab.validate.phase.builtins import CATALOGUE
    from phonglab.validate import validate_phase

    known = CATALOGUE.find("hg (g = 1e-05)").known
    small = validate_phase({"type": "hg", "g": 1e-5}, quick=True, topics=["chi2"], known=known)
    assert small.rows[0].status == "KNOWN"
    # the cause holds at |g| ≤ 1e-3 only: a chi2 failure at g = 0.5 would stay a fail
    from phonglab.validate.known import Known
    (k,) = known["chi2"]
    assert isinstance(k, Known) and not k.holds_at({"g": 0.5})


def test_the_registry_detects_a_phase_function(variant_llvm_rgb):
    from phonglab.validate.registry import detect

    assert detect("hg").name == "phase" and detect({"type": "isotropic"}).name == "phase"
    assert detect("diffuse").name != "phase" and detect("point").name != "phase"


@pytest.mark.parametrize("script", ["hg_small_g_sampling", "sggx_sample_frame_transposed",
                                    "sggx_eval_forward_nan"])
def test_reproducers_exit_1_while_the_behaviour_is_present(script):
    env = {"PYTHONPATH": str(SRC), "PATH": "/usr/bin:/bin"}
    out = subprocess.run([sys.executable, str(REPRO / f"{script}.py")], capture_output=True,
                         text=True, timeout=300, env=env)
    assert out.returncode == 1, out.stdout + out.stderr


def test_xml_spec_and_bad_plugin_file(variant_llvm_rgb, tmp_path):
    from phonglab.validate.inputs import ValidateError
    from phonglab.validate import validate_phase
    from phonglab.validate.registry import detect

    xml = tmp_path / "hg.xml"
    xml.write_text('<phase version="3.0.0" type="hg"><float name="g" value="0.3"/></phase>')
    assert detect(str(xml)).name == "phase"
    report = validate_phase(str(xml), quick=True, topics=["finite", "weight"])
    assert report.passed and report.meta["phase"]
    emitter_file = Path(__file__).parent / "defects_emitter" / "point_control.py"
    with pytest.raises(ValidateError, match="mi.register_phase"):
        validate_phase("defect_point_control", plugins=[emitter_file], quick=True)
