"""The BSDF conformance catalogue (phonglab.validate.bsdf.builtins, .findings; the records in
phonglab.validate.conformance, the renderer phonglab.validate.markdown): cases, documented causes, renderer."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from phonglab.validate import conformance, markdown
from phonglab.validate.bsdf import builtins
from phonglab.validate.bsdf.topics import TOPICS, Row
from phonglab.validate.bsdf import findings
from phonglab.verdict import Report

REPO_ROOT = Path(__file__).resolve().parents[1]

CASES = builtins.cases()
SOURCE_LINE = re.compile(r"^(src|include)/[\w/]+\.(cpp|h):\d+: \S")


def test_labels_unique_and_every_plugin_twice():
    labels = [c.label for c in CASES]
    assert len(labels) == len(set(labels))
    plugins = [c.plugin for c in CASES]
    for name in {c.plugin for c in CASES}:
        assert plugins.count(name) >= 2, name


def test_every_3_9_1_plugin_is_covered_or_left_out():
    # src/bsdfs/*.cpp at tag v3.9.1
    mitsuba = {"blendbsdf", "bumpmap", "circular", "conductor", "dielectric", "diffuse", "hair",
               "mask", "measured", "measured_polarized", "normalmap", "null", "plastic",
               "polarizer", "pplastic", "principled", "principledthin", "retarder",
               "roughconductor", "roughdielectric", "roughplastic", "thindielectric", "twosided"}
    covered = {c.plugin for c in CASES} | set(builtins.LEFT_OUT)
    assert mitsuba <= covered
    assert {"lambert", "phong"} <= covered


def test_every_known_entry_names_a_source_line():
    assert any(c.known for c in CASES)
    for case in CASES:
        for topic, causes in case.known.items():
            assert topic in TOPICS, (case.label, topic)
            for k in causes:
                assert SOURCE_LINE.match(k.cause), (case.label, k.cause)
                assert k.rows, (case.label, k.key)      # a signature names its rows


def test_findings_name_existing_cases_and_reproducers():
    labels = {c.label for c in CASES}
    for f in findings.FINDINGS:
        assert set(f.labels) <= labels, f.key
        assert (REPO_ROOT / f.reproducer).is_file(), f.reproducer
        assert f.topic in TOPICS


@pytest.mark.parametrize("case", CASES, ids=[c.label for c in CASES])
def test_case_loads_in_its_variant(case):
    import mitsuba as mi   # after builtins.load's first call has pinned libLLVM (runtime)
    bsdf = builtins.load(case)
    assert mi.variant() == case.resolved_variant()
    assert isinstance(bsdf, mi.BSDF)
    delta = int(mi.BSDFFlags.Delta | mi.BSDFFlags.Null)
    lobes = [int(bsdf.flags(i)) for i in range(bsdf.component_count())]
    assert case.delta == all(f & delta for f in lobes), case.label


def _row(topic, status, name="cell"):
    return Row(topic, name, 1.5, 1.0, 0.1, 0.3, status, "why" if status != "pass" else "", {})


def test_markdown_renders_a_given_json():
    label = "roughplastic/beckmann-a0.25"
    case = next(c for c in CASES if c.label == label)
    rows = [_row("finite", "pass"), _row("chi2", "KNOWN", "45 deg"), _row("energy", "fail"),
            _row("gradient", "skipped")]
    report = Report({"case": label, "variant": "llvm_ad_rgb", "note": case.note,
                     "spec": {"type": "roughplastic", "alpha": 0.25},
                     "known": {t: [k.describe() for k in v] for t, v in case.known.items()}},
                    rows).to_dict()
    data = {"meta": {"options": {"quick": True, "seed": 3}, "seconds": 12.5},
            "reports": [report]}
    md = markdown.render_markdown(data)
    table_row = next(line for line in md.splitlines() if line.startswith(f"| `{label}`"))
    cells = [c.strip() for c in table_row.strip("|").split("|")][3:]   # after case, variant, points
    assert dict(zip(TOPICS, cells)) == {
        "finite": "pass", "eval_pdf": "", "weight": "", "pdf": "", "chi2": "KNOWN",
        "normalization": "", "energy": "**fail**", "reciprocity": "", "component": "",
        "eval_null_transmission": "", "eval_diffuse_reflectance": "", "mueller": "",
        "intensity": "", "mueller_identities": "", "mueller_reciprocity": "", "gradient": "skipped",
        "cost": ""}
    assert "1 pass, 1 fail, 1 KNOWN, 1 skipped rows, 12.5 s" in md
    assert "src/bsdfs/roughplastic.cpp#L422" in md
    assert "tests/repro/roughplastic_pdf_below_horizon.py" in md
    assert "**Unexplained fail** (energy)" in md
    for name in builtins.LEFT_OUT:
        assert f"* `{name}`:" in md


def test_markdown_lists_a_finding_only_under_the_rows_it_explains():
    # roughdielectric/polarized (eta 1.5): its normalization row is Beckmann's, never the
    # index-matched finding's (eta in [0.999, 1.001]), though both name the case
    label = "roughdielectric/polarized"
    case = next(c for c in CASES if c.label == label)
    rows = [Row("normalization", "∫ pdf dω_o = P(sample counted)", 0.998, 1.0, 1e-5, 1e-4,
                "KNOWN", "why", {"known_by": ["beckmann-pdf-normalization"]})]
    report = Report({"case": label, "variant": "llvm_ad_rgb", "note": case.note,
                     "spec": case.spec}, rows).to_dict()
    md = markdown.render_markdown({"meta": {"options": {}}, "reports": [report]})
    section = md.split(f"### `{label}`")[1].split("## Findings")[0]
    assert "(#beckmann-pdf-normalization)" in section
    assert "index-matched" not in section
    explained, idle = md.split("## Findings that explain no row of this run")
    assert "### beckmann-pdf-normalization" in explained
    assert "### roughdielectric-index-matched-normalization" in idle


def test_cell_status_order():
    rows = [{"status": s} for s in ("pass", "skipped", "KNOWN")]
    assert markdown.cell_status(rows) == "KNOWN"
    assert markdown.cell_status(rows + [{"status": "fail"}]) == "fail"
    assert markdown.cell_status([]) == ""


def test_script_renders_from_json(tmp_path):
    import json
    import subprocess
    import sys
    data = {"meta": {"options": {"quick": True, "seed": 0}}, "reports": []}
    src = tmp_path / "c.json"
    src.write_text(json.dumps(data))
    out = tmp_path / "c.md"
    subprocess.run([sys.executable, str(REPO_ROOT / "scripts" / "conformance.py"),
                    "--kind", "bsdf", "--from-json", str(src), "--markdown", str(out)],
                   check=True, capture_output=True)
    assert out.read_text().startswith("# Conformance of Mitsuba 3.9.1")
    assert Path(out).stat().st_size > 0


def test_without_plot_data_keeps_the_numbers():
    data = {"meta": {}, "reports": [{"meta": {"case": "x"}, "results": [
        {"topic": "energy", "details": {"albedo": [0.5], "lobes": {"theta": [1, 2]}}},
        {"topic": "chi2", "details": {"cells": [
            {"p_value": 0.3, "status": "pass", "messages": "Accepted", "histogram": [[1, 2]]},
            {"p_value": 0.0, "status": "fail", "messages": "Rejected", "pdf": [[1.0, 2.0]]}]}}]}]}
    out = markdown.without_plot_data(data)
    energy, chi2 = out["reports"][0]["results"]
    assert energy["details"] == {"albedo": [0.5]}
    assert chi2["details"] == {"cells": [{"p_value": 0.3, "status": "pass"},
                                         {"p_value": 0.0, "status": "fail",
                                          "messages": "Rejected"}]}
    assert "lobes" in data["reports"][0]["results"][0]["details"]    # the input is untouched


def _one_row(label, topic, status):
    report = Report({"case": label, "variant": "llvm_ad_rgb"}, [_row(topic, status)]).to_dict()
    return {"meta": {"options": {}}, "reports": [report]}


def test_open_validator_issue_shown_only_for_its_failing_rows(monkeypatch):
    labels = ("roughconductor/beckmann-novisible", "roughdielectric/beckmann-a0.1")
    issue = conformance.ValidatorIssue("open-issue", "weight", labels, "why")
    monkeypatch.setattr(builtins, "VALIDATOR_ISSUES", (issue,))
    label = issue.labels[0]
    assert builtins.catalogue().open_issues() == {(x, "weight"): issue for x in labels}
    md = markdown.render_markdown(_one_row(label, issue.topic, "fail"))
    assert "### open-issue" in md and "**Unexplained fail**" not in md
    assert f"* cases: `{label}`\n" in md            # only the case whose row shows
    assert "because of the validator" not in markdown.render_markdown(
        _one_row(label, issue.topic, "pass"))
    skipped = conformance.ValidatorIssue("open-skip", "chi2", labels, "why", ("skipped",))
    monkeypatch.setattr(builtins, "VALIDATOR_ISSUES", (skipped,))
    assert "### open-skip" in markdown.render_markdown(_one_row(label, "chi2", "skipped"))


def test_committed_conformance_json_has_no_unexplained_fail():
    """docs/conformance.json: every fail row is explained by an open validator issue (the
    Mitsuba findings' rows are KNOWN)."""
    import json
    data = json.loads((REPO_ROOT / "docs" / "conformance.json").read_text())
    open_issues = builtins.catalogue().open_issues()
    fails = [(rep["meta"]["case"], r["topic"]) for rep in data["reports"]
             for r in rep["results"] if r["status"] == "fail"]
    assert [f for f in fails if f not in open_issues] == []


REPRODUCERS = sorted({f.reproducer for f in findings.FINDINGS})


@pytest.mark.slow
@pytest.mark.parametrize("script", REPRODUCERS)
def test_reproducer_shows_its_finding_in_mitsuba_3_9_1(script):
    """Each tests/repro script exits 1 while the behaviour it documents is present (3.9.1)."""
    import subprocess
    import sys

    from phonglab import runtime
    runtime.configure()      # pins libLLVM before Mitsuba (and Dr.Jit) load
    import mitsuba as mi
    if mi.__version__ != conformance.MITSUBA_VERSION:
        pytest.skip(f"the findings are pinned to Mitsuba {conformance.MITSUBA_VERSION}")
    done = subprocess.run([sys.executable, str(REPO_ROOT / script)], capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 1, done.stdout + done.stderr
