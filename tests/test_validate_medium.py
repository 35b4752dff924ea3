"""The medium validator (the fifth kind): Mitsuba's built-in homogeneous and heterogeneous
pass, each planted defect fails its own topic (and the transmittance its integrators' tracking
then shows), the controls pass, the catalogue's failing rows are KNOWN by their findings, the
reproducers exit 1, and a medium is validated by name, --plugin file, XML file, loaded object
and assert_medium_valid.

Quick sizes and seed 0; the transmittance rows are tests at the family-wise level ALPHA = 0.01
per medium (Šidák over its rays, channels and estimators, and the phase function's χ²), so a
correct medium fails a run with probability ≤ 1 %; the other topics are deterministic.
"""

from __future__ import annotations

import runpy
import subprocess
import sys
from pathlib import Path

import pytest

from phonglab.validate.medium.topics import TOPICS

HERE = Path(__file__).parent
DEFECTS = HERE / "defects_medium"
REPRO = HERE / "repro"
SRC = HERE.parent / "src"

#: defect file -> the topics it must fail (empty: a control); the first is its own
PLANTED = {
    "blob_control": set(),
    "fog_control": set(),
    "nan_density": {"finite"},
    "majorant_from_p": {"majorant", "transmittance"},
    "sigma_n_negative": {"majorant", "transmittance"},
    "sigma_a_for_sigma_n": {"majorant", "transmittance"},
    "albedo_above_one": {"albedo"},
    "aabb_too_small": {"bounds"},
    "spectral_flag_unset": {"flags", "transmittance"},
    "homogeneous_flag_set": {"flags", "transmittance"},
    "ignored_override": {"overrides"},
    "wrong_gradient": {"gradient"},
}
#: the row each defect's own topic fails by
OWN_ROW = {
    "majorant_from_p": "σ_t + σ_n = majorant", "sigma_n_negative": "σ_n ≥ 0",
    "sigma_a_for_sigma_n": "σ_t + σ_n = majorant",
    "spectral_flag_unset": "has_spectral_extinction where σ_t's channels differ",
    "homogeneous_flag_set": "is_homogeneous only where σ_n = 0 and σ_t = majorant",
    "ignored_override": "sample_interaction() overridden",
    "wrong_gradient": "albedo: σ_s",
}


@pytest.mark.parametrize("name", sorted(PLANTED))
def test_defect_fails_its_topic(variant_llvm_rgb, name):
    from phonglab.validate import validate_medium

    report = validate_medium(f"defect_{name}", plugins=[DEFECTS / f"{name}.py"], quick=True)
    assert {r.topic for r in report.failing} == PLANTED[name], report.table(report.failing)
    assert {r.topic for r in report.rows} == set(TOPICS)
    if name in OWN_ROW:
        assert OWN_ROW[name] in {r.name for r in report.failing}


def test_a_defective_phase_function_fails_the_phase_topic(variant_llvm_rgb):
    """The phase topic is the phase kind's own validation of the medium's phase function."""
    from phonglab.validate import validate_medium

    runpy.run_path(str(HERE / "defects_phase" / "hg_opposite_g.py"))
    spec = {"type": "homogeneous", "phase": {"type": "defect_hg_opposite_g"}}
    report = validate_medium(spec, quick=True, topics=["phase"])
    failing = {r.name for r in report.failing}
    assert failing == {"chi2: sampling matches eval_pdf (min p-value)"}, report.table()


def test_every_topic_but_cost_has_a_planted_defect():
    assert set().union(*PLANTED.values()) | {"cost", "phase"} == set(TOPICS)


@pytest.mark.parametrize("spec", [{"type": "homogeneous", "sigma_t": 2.0},
                                  {"type": "heterogeneous", "sigma_t": "blob"}],
                         ids=["homogeneous", "heterogeneous-blob"])
def test_builtin_media_pass(variant_llvm_rgb, spec):
    from phonglab.validate import validate_medium
    from phonglab.validate.medium.builtins import blob, grid

    if spec["sigma_t"] == "blob":
        spec = {**spec, "sigma_t": grid(blob())}
    report = validate_medium(spec, quick=True)
    assert report.passed, report.table(report.failing)
    assert not any(r.status == "KNOWN" for r in report.rows)
    assert report.meta["kind"] == "medium" and report.meta["statistical_tests"] > 3


@pytest.mark.slow
def test_catalogue_passes_with_its_findings(variant_llvm_rgb):
    from phonglab.validate import validate_medium
    from phonglab.validate.medium.builtins import CATALOGUE

    for case in CATALOGUE.cases():
        report = validate_medium(case.spec, quick=True, known=case.known)
        assert report.passed, (case.label, report.table(report.failing))


def test_microflake_majorant_findings_are_known_by_their_rows(variant_llvm_rgb):
    from phonglab.validate import validate_medium
    from phonglab.validate.medium.builtins import CATALOGUE, HET_SGGX_LARGE

    case = CATALOGUE.find(HET_SGGX_LARGE)
    plain = validate_medium(case.spec, quick=True, topics=["majorant"])
    assert {r.name for r in plain.failing} == {"σ_n ≥ 0"}
    marked = validate_medium(case.spec, quick=True, topics=["majorant"], known=case.known)
    assert marked.passed and marked.rows[1].details["known_by"] == [
        "heterogeneous-microflake-majorant"]


@pytest.mark.parametrize("script", ["heterogeneous_volume_outside_bounds",
                                    "heterogeneous_microflake_majorant",
                                    "homogeneous_microflake_majorant_at_origin"])
def test_reproducers_exit_1_while_the_behaviour_is_present(script):
    env = {"PYTHONPATH": str(SRC), "PATH": "/usr/bin:/bin"}
    out = subprocess.run([sys.executable, str(REPRO / f"{script}.py")], capture_output=True,
                         text=True, timeout=300, env=env)
    assert out.returncode == 1, out.stdout + out.stderr


def test_the_registry_detects_a_medium(variant_llvm_rgb, tmp_path):
    from phonglab.validate.registry import detect

    assert detect("homogeneous").name == "medium" and detect("heterogeneous").name == "medium"
    xml = tmp_path / "m.xml"
    xml.write_text('<medium version="3.0.0" type="homogeneous">'
                   '<float name="sigma_t" value="2"/></medium>\n')
    assert detect(str(xml)).name == "medium"


def test_cli_by_name_plugin_file_and_xml(variant_llvm_rgb, tmp_path, capsys):
    from phonglab.cli import main

    assert main(["validate", "homogeneous", "--quick", "--only", "majorant"]) == 0
    assert main(["validate", "defect_fog_control", "--quick", "--only", "flags",
                 "--plugin", str(DEFECTS / "fog_control.py")]) == 0
    assert main(["validate", "defect_albedo_above_one", "--quick", "--only", "albedo",
                 "--plugin", str(DEFECTS / "albedo_above_one.py")]) == 1
    xml = tmp_path / "fog.xml"
    xml.write_text('<medium version="3.0.0" type="homogeneous">'
                   '<float name="sigma_t" value="2"/><phase type="hg">'
                   '<float name="g" value="0.5"/></phase></medium>\n')
    assert main(["validate", str(xml), "--quick", "--only", "transmittance"]) == 0
    out = capsys.readouterr().out
    assert "medium" in out


def test_assert_medium_valid_and_a_loaded_medium(variant_llvm_rgb):
    import drjit as dr
    import mitsuba as mi

    from phonglab.testing import assert_medium_valid

    assert_medium_valid("defect_blob_control", plugins=[DEFECTS / "blob_control.py"],
                        quick=True, topics=["finite", "majorant", "bounds"])
    with pytest.raises(AssertionError, match="bounds"):
        assert_medium_valid("defect_aabb_too_small", plugins=[DEFECTS / "aabb_too_small.py"],
                            quick=True, topics=["bounds"])

    class Agreeing(mi.Medium):
        """A grey fog that also overrides is_homogeneous() with what the field holds."""

        def __init__(self, props):
            mi.Medium.__init__(self, props)
            self.m_is_homogeneous = True
            self.m_has_spectral_extinction = False

        def is_homogeneous(self):
            return True

        def intersect_aabb(self, ray):
            return mi.Bool(True), mi.Float(0.0), mi.Float(dr.inf)

        def get_majorant(self, mei, active=True):
            return mi.UnpolarizedSpectrum(1.0)

        def get_scattering_coefficients(self, mei, active=True):
            return (mi.UnpolarizedSpectrum(0.5), mi.UnpolarizedSpectrum(0.0),
                    mi.UnpolarizedSpectrum(1.0))

        def to_string(self):
            return "Agreeing[]"

    report = assert_medium_valid(Agreeing(mi.Properties()), quick=True, topics=["overrides"])
    (row,) = report.rows
    assert row.status == "pass" and "changes nothing" in row.reason


def test_catalogue_covers_3_9_1_and_its_findings_are_pinned(variant_llvm_rgb):
    """src/media/*.cpp at v3.9.1: homogeneous and heterogeneous; every finding names cases of
    the table, a source line, an existing reproducer, and reaches its cases as a signature."""
    import re

    from phonglab.validate import registry

    cat = registry.catalogue("medium")
    cases = cat.cases()
    labels = [c.label for c in cases]
    assert len(labels) == len(set(labels))
    assert {"homogeneous", "heterogeneous"} <= {c.plugin for c in cases} | set(cat.left_out)
    source = re.compile(r"^(src|include)/[\w/]+\.(cpp|h|py):\d+$")
    known = {c.label: c.known for c in cases}
    for f in cat.findings:
        assert set(f.labels) <= set(labels) and f.topic in cat.kind.topics and f.rows, f.key
        assert source.match(f.source) and (HERE.parent / f.reproducer).is_file(), f.key
        for label in f.labels:
            assert f.key in {k.key for k in known[label][f.topic]}
    assert cat.markdown == "docs/conformance-media.md" and (HERE.parent / cat.markdown).is_file()


def test_a_sweep_varies_the_documented_parameters_and_judges_the_phase_once(variant_llvm_rgb):
    """homogeneous is swept over albedo, sigma_t and scale (Mitsuba's documented domains,
    medium.ranges.BUILTIN); the phase function comes from the properties, which no swept
    parameter changes, so its topic runs at the given point only; the gradient topic runs at
    every point."""
    from phonglab.validate import validate_medium

    report = validate_medium("homogeneous", quick=True, topics=["phase", "gradient", "albedo"],
                             sweep=True)
    swept = report.meta["sweep"]["parameters"]
    assert {p["name"] for p in swept} == {"albedo", "sigma_t", "scale"}, swept
    assert {p["source"] for p in swept} == {"mitsuba"}
    points = {tuple(sorted(r.point.items())) for r in report.rows}
    assert len(points) > 3
    assert {tuple(sorted(r.point.items())) for r in report.rows if r.topic == "phase"} == {()}
    assert {tuple(sorted(r.point.items())) for r in report.rows if r.topic == "gradient"} \
        == points
    assert report.passed, report.table(report.failing)
