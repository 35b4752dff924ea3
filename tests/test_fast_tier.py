"""The fast tier's record (phonglab.bench.fast_tier): pytest's summary read from its output,
and the BENCHMARKS.md section rendered from a made-up record (nothing timed here)."""

from __future__ import annotations

import json

from phonglab.bench import fast_tier
from phonglab.bench.report_data import RunData


def _data(folder) -> RunData:
    return RunData(out=folder, rel=".", run={}, results=[], stab=[], ratios=[], jit=[],
                   quick=None)


def _run(mode: str, seconds: float, failed: int = 0, load_before: float = 0.5) -> dict:
    return {"mode": mode, "seconds": seconds, "pytest_seconds": seconds - 1.0,
            "passed": 1500 - failed, "failed": failed, "load_before": load_before,
            "load_after": 1.9}


def _section(folder, runs) -> str:
    """BENCHMARKS.md's section of a record holding ``runs``."""
    (folder / fast_tier.JSON_NAME).write_text(json.dumps(
        {"commit": "abc1234", "cores": 2, "setup_seconds": 25.0, "runs": runs}))
    return "\n".join(fast_tier.report_section(_data(folder)))


def test_summary_reads_the_last_pytest_line():
    out = "....\n1 passed in 2.00s\n...\n1502 passed, 3 warnings in 151.34s (0:02:31)\n"
    assert fast_tier.summary(out) == {"passed": 1502, "failed": 0, "pytest_seconds": 151.34}
    assert fast_tier.summary("2 failed, 1499 passed in 160.0s")["failed"] == 2
    assert fast_tier.summary("error: no tests ran")["passed"] is None


def test_section_states_each_run_against_its_aim(tmp_path):
    text = _section(tmp_path, [_run("cold", 210.0, load_before=0.1), _run("warm", 140.0),
                               _run("warm", 151.0, failed=1, load_before=0.4)])
    rows = [line for line in text.splitlines() if line.startswith("| cold") or
            line.startswith("| warm")]
    assert len(rows) == 3
    assert rows[0].endswith("**not met** |")       # 210 s cold against 200
    assert rows[1].endswith("**met** |")           # 140 s warm against 150
    assert rows[2].endswith("**not met** |")       # a failed test is never met
    assert "median 145.5 s over 2 runs" in text


def test_no_record_no_section(tmp_path):
    assert fast_tier.report_section(_data(tmp_path)) == []


def test_a_run_with_the_machines_own_home_is_its_own_row_and_says_why(tmp_path):
    text = _section(tmp_path, [_run("cold", 215.0, load_before=0.1), _run("warm", 165.0),
                               _run("own HOME", 142.0, load_before=0.4)])
    (own,) = [line for line in text.splitlines() if line.startswith("| warm, own `HOME`")]
    assert own.endswith("**met** |")               # 142 s against the warm aim, 150
    assert "median 165.0 s over 1 runs" in text    # the own-HOME run is not a warm one
    assert "kernel's IR depends on what ran before it" in text
