"""phonglab.verdict, the one result record: statuses, strict JSON, the table's cells."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from phonglab import verdict
from phonglab.engine.outputs import write_json
from phonglab.verdict import Report, Row


def test_row_refuses_unknown_status_but_takes_any_topic():
    with pytest.raises(ValueError, match="unknown status"):
        Row("energy", "x", 1.0, 1.0, 0.0, 0.0, "FAIL", "")
    assert Row("any check", "x", 1.0, 1.0, 0.0, 0.0, "pass", "").topic == "any check"


def test_json_is_strict_and_round_trips(tmp_path):
    row = Row("t", "n", math.nan, np.float32(0.5), None, math.inf, "fail", "why",
              {"a": np.arange(3), "b": np.bool_(True), "c": np.int64(7), "p": Path("x/y.exr"),
               (1, 2): (np.float64(-math.inf),)})
    report = Report({"seed": np.int32(3)}, [row])
    d = json.loads(json.dumps(report.to_dict(), allow_nan=False))
    assert d["meta"] == {"seed": 3}
    r = d["results"][0]
    assert list(r) == ["topic", "name", "measured", "expected", "stderr", "tolerance", "status",
                       "reason", "details"]
    assert (r["measured"], r["expected"], r["tolerance"]) == ("nan", 0.5, "inf")
    assert r["details"] == {"a": [0, 1, 2], "b": True, "c": 7, "p": "x/y.exr",
                            "(1, 2)": ["-inf"]}
    path = write_json(tmp_path / "sub" / "r.json", report.to_dict())
    assert json.loads(path.read_text()) == d
    assert Report.from_dict(d).rows[0].details == r["details"]
    assert not report.passed and report.failing == [row]


def test_table_cells_relation_stderr_and_reasons():
    rows = [Row("chi2", "p", 0.123456789, 0.001, 0.0, 0.0, "pass", "p-value",
                {"relation": ">="}),
            Row("energy", "rho", 0.5, None, None, None, "skipped", "")]
    assert verdict.cells(rows[0]) == ("pass", "chi2", "p", "0.1235", "≥ 0.001", "0")
    assert verdict.cells(rows[0], digits=6, stderr=True) == ("pass", "chi2", "p", "0.123457",
                                                             "≥ 0.001", "0", "0")
    assert verdict.cells(rows[1]) == ("skipped", "energy", "rho", "0.5", "-", "-")
    text = verdict.table(rows)
    assert text.splitlines()[0].split() == list(verdict.header())
    assert "p-value" in text
    assert "p-value" not in verdict.table(rows, reasons=False)
    assert "stderr" in verdict.table(rows, stderr=True).splitlines()[0]


def test_the_summary_line_says_measured_and_expected_not_against_the_tolerance():
    """The summary puts the expected value where a reader expects it, the tolerance beside it
    (not ``(1.005 against 6.919e-05)``); a ratio-to-tolerance row says what its number is."""
    energy = Row("energy", "directional albedo ≤ 1", 1.005, 1.0, None, 6.919e-05, "fail", "r",
                 {"relation": "<="}, point={})
    assert verdict.summary(energy) == "measured 1.005, expected ≤ 1 (tolerance 6.919e-05)"
    ratio = Row("weight", "weight = eval/pdf", 1018.0, 0.0, None, 1.0, "fail",
                "measured = max over lanes of rel_diff / (2^-10 + ...), must be ≤ 1", {})
    assert verdict.summary(ratio) == "max relative error / its tolerance = 1018, must be ≤ 1"
    chi2 = Row("chi2", "sampling matches pdf (min p-value)", 0.169, 1e-3, None, 1e-3, "fail",
               "r", {"cells": [{"status": "fail", "problems": [
                   "the pdf integrates to 3.1416 over the sphere, expected ≤ 1 (refused above "
                   "1.1)"]}]})
    assert verdict.summary(chi2) == ("min p-value 0.169, level 0.001; the pdf integrates to "
                                     "3.1416 over the sphere, expected ≤ 1 (refused above 1.1)")
    text = verdict.table_by_point([energy])
    assert "against" not in text and "measured 1.005, expected ≤ 1" in text


def test_an_advice_row_does_not_fail_and_is_counted():
    row = Row("energy", "directional albedo ≤ 1", 9499.0, 1.0, None, 0.1, "advice", "r",
              {"relation": "<="}, point={"kd": 1e4})
    report = Report({}, [row])
    assert report.passed and Row.from_dict(row.to_dict()).status == "advice"
    assert "advice energy" in verdict.table_by_point(report.rows)


def test_a_chi2_cell_is_rejected_for_its_real_reason():
    from phonglab.validate.bsdf.sampling import why_rejected
    cell = {"p_value": 0.169, "problems": ["the pdf integrates to 3.1416 over the sphere, "
                                           "expected ≤ 1 (refused above 1.1)"]}
    assert why_rejected(cell, 1e-3).startswith("the pdf integrates to 3.1416 over the sphere")
    assert "p = 0.169 ≥ the level" in why_rejected(cell, 1e-3)
    assert why_rejected({"p_value": 1e-9}, 1e-3) == "p = 1e-09, below the level 0.001"


def test_every_html_figure_is_labelled_with_its_point():
    """A sweep's figure blocks are labelled with their points, not identical sections."""
    from phonglab.validate import html
    details = {"relation": "<=", "theta_deg": [0.0, 45.0], "albedo": [0.5, 0.5],
               "band": [1e-5, 1e-5]}
    rows = [Row("energy", "directional albedo ≤ 1", 0.5, 1.0, None, 1e-5, "pass", "r",
                dict(details), point=p) for p in ({}, {"kd": 0.0}, {"kd": 1.0})]
    page = html.render(Report({"bsdf": "x"}, rows))
    for label in ("given", "kd=0", "kd=1"):
        assert f"<h2>Directional albedo at {label}</h2>" in page
    assert "<th>point</th>" in page
