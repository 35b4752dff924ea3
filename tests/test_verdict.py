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
