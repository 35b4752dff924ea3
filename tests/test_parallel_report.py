"""scripts/cluster_bench.py's arithmetic and BENCHMARKS.md's cluster section, on a small record.

The record is built by the script's own functions from hand-made timings, so the figures the
section prints can be checked against the formula T_N = here + Σ_batches [max(M, S/N) + o·C/N]
computed here by hand.
"""

from __future__ import annotations

import copy
import importlib.util
import json
from pathlib import Path

import pytest

from phonglab.bench import report
from phonglab.bench.cluster_report import cluster_section
from phonglab.bench.report_data import RunData

REPO_ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def cb():
    spec = importlib.util.spec_from_file_location("cluster_bench",
                                                  REPO_ROOT / "scripts" / "cluster_bench.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


BENCH_JOBS = {"estimators": {"count": 90, "sum_s": 4.0, "median_s": 0.01, "max_s": 0.6,
                             "longest": "estimators"},
              "ratios": {"count": 25, "sum_s": 20.0, "median_s": 0.8, "max_s": 3.0,
                         "longest": "ratios"}}
VALIDATE_JOBS = {"cases": {"count": 54, "sum_s": 54.0, "median_s": 0.7, "max_s": 7.0,
                           "longest": "hair/blond-rough"}}
O_MS = 6.0


def _record(cb) -> dict:
    bench = [{"order": o, "wall_s": {"serial": s, "workers": w}, "jobs": BENCH_JOBS}
             for o, s, w in ((["serial", "workers"], 40.0, 50.0), (["workers", "serial"], 44.0, 46.0))]
    validate = [{"order": ["serial", "workers"], "wall_s": {"serial": 60.0, "workers": 75.0},
                 "jobs": VALIDATE_JOBS, "identical": True}]
    return {"workers": 2, "budget_s": 360.0, "machine": {"cores": 2},
            "load_before": [4.5, 5.0, 6.0], "load_after": [5.5, 5.0, 6.0],
            "n_values": list(cb.N_VALUES),
            "overhead": {"jobs": 300, "repeats": 5,
                         "serial_per_job_ms": cb.spread([0.09, 0.1, 0.12], 4),
                         "local_per_job_ms": cb.spread([5.0, O_MS, 9.0]), "local_start_s": 4.6},
            "bench": cb.summarize("bench", bench, O_MS),
            "validate": cb.summarize("validate", validate, O_MS)}


def test_expected_time_on_n_machines_is_the_stated_formula(cb):
    rec = _record(cb)
    here = 42.0 - 24.0                      # median serial wall − Σ S of the bench
    for n in cb.N_VALUES:
        by_hand = here + sum(max(j["max_s"], j["sum_s"] / n) + O_MS / 1e3 * j["count"] / n
                             for j in BENCH_JOBS.values())
        assert rec["bench"]["on_n"]["total_s"][str(n)] == pytest.approx(by_hand, abs=0.06)
    # The longest job bounds it: the estimators' S/N falls below M from N = ceil(4/0.6) = 7 on.
    assert rec["bench"]["on_n"]["bound_from_n"] == {"estimators": 7, "ratios": 7}
    assert rec["bench"]["on_n"]["longest_job"] == {"batch": "ratios", "job": "ratios", "seconds": 3.0}
    assert rec["validate"]["on_n"]["batches"]["cases"]["64"] == pytest.approx(7.0 + 0.006 * 54 / 64,
                                                                            abs=0.006)
    assert rec["bench"]["speedup"]["values"] == [0.8, round(44 / 46, 3)]
    assert rec["bench"]["serial_s"]["median"] == 42.0


def test_without_timings_drops_only_the_timing_fields(cb):
    a = {"meta": {"cases": 1}, "reports": [{"meta": {"case": "diffuse/0.5", "seconds": 0.5,
                                                    "wall_seconds": 0.6, "topic_seconds": {"chi2": 0.2}},
                                           "results": [
        {"topic": "chi2", "name": "chi2 at 30 deg", "measured": 0.41, "status": "pass"},
        {"topic": "cost", "name": "eval time", "measured": 0.21, "details": {"seconds": 1e-3},
         "status": "pass"}]}]}
    b = copy.deepcopy(a)
    b["reports"][0]["meta"].update(seconds=0.9, wall_seconds=1.1, topic_seconds={"chi2": 0.4})
    b["reports"][0]["results"][1].update(measured=0.35, details={"seconds": 2e-3})
    assert cb.without_timings(a) == cb.without_timings(b)
    b["reports"][0]["results"][0]["measured"] = 0.42          # a result, not a timing
    assert cb.without_timings(a) != cb.without_timings(b)
    b = copy.deepcopy(a)
    b["reports"][0]["results"][1]["status"] = "fail"         # a cost row's status still counts
    assert cb.without_timings(a) != cb.without_timings(b)
    # mi.chi2's messages carry durations: masked, the statistic next to them still compared
    text = "Histogram sum = 1.000000 (25.56 ms), PDF sum = 1.000007 (11.52 ms)\nChi^2 statistic = 851.47"
    a["reports"][0]["results"][0]["details"] = {"cells": [{"messages": text}]}
    b = copy.deepcopy(a)
    b["reports"][0]["results"][0]["details"]["cells"][0]["messages"] = \
        text.replace("25.56 ms", "35.04 ms").replace("11.52 ms", "90.38 ms")
    assert cb.without_timings(a) == cb.without_timings(b)
    b["reports"][0]["results"][0]["details"]["cells"][0]["messages"] = text.replace("851.47", "851.48")
    assert cb.without_timings(a) != cb.without_timings(b)


def _data(tmp_path) -> RunData:
    return RunData(out=tmp_path, rel=".", run={}, results=[], stab=[], ratios=[], jit=[], quick=None)


def test_cluster_section_renders_the_record(cb, tmp_path):
    (tmp_path / "cluster.json").write_text(json.dumps(_record(cb)))
    text = "\n".join(cluster_section(_data(tmp_path)))
    assert "| `phonglab bench --quick --fresh` | 2 | 42 [40, 44] | 48 [46, 50] | 0.878 [0.8, 0.957] |" in text
    assert "| 1 | 60 [60, 60] | 75 [75, 75] | 0.8 [0.8, 0.8] |" in text
    assert "identical apart from their timing fields (`seconds`, `topic_seconds`, `wall_seconds`" in text
    assert "**not** identical" not in text
    assert ("median speed-ups: `phonglab bench --quick --fresh` 0.878, `phonglab validate "
            "--all-builtins --quick` 0.8)") in text and "More machines add cores" in text
    assert "> **Note:** measured while other processes shared the 2 cores" in text   # load 5.5
    assert "| LocalCluster(2) | 6 [5, 9] | 4.6 |" in text
    # N = 16: bench estimators max(0.6, 4/16) + 0.006·90/16 = 0.634; validate total 7 + here (60 − 54)
    assert "| bench: estimators | 90 | 4 | 0.6 | 4.54 | 2.27 | 1.14 | 0.67 | 0.63 | 0.61 |" in text
    assert "| **validate: total** |" in text and "**13**" in text
    assert "`hair/blond-rough` (7 s)" in text and "one of its `ratios` jobs (3 s)" in text


def test_cluster_section_is_skipped_without_its_record(tmp_path):
    assert cluster_section(_data(tmp_path)) == []
    assert report.SECTIONS.index(cluster_section) == report.SECTIONS.index(report.reproduce_section) - 1
