"""phonglab.bench and ``phonglab bench``: the harness's own pieces (Pareto front, resumable CSV,
verdict rule, scene swaps), then one small real run through the CLI that must resume."""

from __future__ import annotations

import csv
import json
import math

import pytest

from phonglab import bench
from phonglab.cli import main
from phonglab.errors import PhonglabError
from phonglab.engine.metrics import errors
from phonglab.physics.estimators import METHODS
from phonglab.physics.roughness import beckmann_alpha


def test_pareto_front_keeps_only_undominated_points():
    pts = [(1.0, 0.5), (2.0, 0.3), (2.5, 0.4), (3.0, 0.1), (0.5, 0.9), (4.0, 0.1),
           (1.5, float("nan")), (5.0, 0.0)]
    assert bench.pareto_front(pts) == [(0.5, 0.9), (1.0, 0.5), (2.0, 0.3), (3.0, 0.1)]


def test_csv_log_writes_row_by_row_and_resumes(tmp_path):
    path = tmp_path / "r.csv"
    log = bench.CsvLog(path, ["a", "b", "x"], ("a", "b"))
    log.add({"a": "m", "b": 1, "x": 0.25})
    assert path.read_text().splitlines() == ["a,b,x", "m,1,0.25"]   # on disk at once
    again = bench.CsvLog(path, ["a", "b", "x"], ("a", "b"))
    assert again.has(a="m", b=1) and not again.has(a="m", b=2)
    with pytest.raises(PhonglabError, match="--fresh"):
        bench.CsvLog(path, ["a", "b", "y"], ("a", "b"))


@pytest.mark.parametrize("args,verdict,reason", [
    ((0.05, 0.0, 0.3, 0), "ok", ""),
    ((0.05, 0.0, 0.3, 2), "breaks down", "NaN/Inf"),
    ((0.5, -0.01, 0.3, 0), "breaks down", "noise"),
    ((1.0, -1.0, math.inf, 0), "breaks down", "silent"),
    ((0.05, -0.04, 9.0, 0), "breaks down", "unexplained"),
    ((1e-5, 1e-5, 50.0, 0), "ok", ""),          # float32 rounding of a near-exact estimate
])
def test_stability_verdict_rule(args, verdict, reason):
    v, r = bench.stability_verdict(*args, z_crit=4.2)
    assert v == verdict and reason in r


@pytest.mark.parametrize("boxes,expect", [("phong", 'type="phong"'), ("plastic", 'type="plastic"'),
                                          ("roughplastic", 'name="alpha"'), ("lambert", 'type="lambert"')])
def test_cornell_variants_swap_only_the_boxes(boxes, expect):
    xml = bench.cornell_xml(boxes)
    assert expect in xml and '<rfilter type="box"/>' in xml
    assert xml.count('id="glossy">') == 1 and xml.count('type="$wall"') == 3


def test_cornell_variants_load_and_bad_box_is_a_clear_error(variant_llvm_rgb):
    for boxes in bench.BOX_TYPES:
        scene = bench.CornellSpec(walls="diffuse", boxes=boxes, res=4).load()
        assert scene.shapes()
    with pytest.raises(PhonglabError, match="unknown box material"):
        bench.cornell_xml("glass")


def test_beckmann_alpha_matches_lobe_width():
    """α_b = √(2/(4p+2)): the half-vector width of cos^p α (α ≈ 2θ_h) equals Beckmann's."""
    assert beckmann_alpha(30.0) == pytest.approx(math.sqrt(2 / 122))
    assert beckmann_alpha(1e4) == pytest.approx(1 / math.sqrt(2e4), rel=1e-4)


def test_timing_driver_times_a_fresh_process(tmp_path):
    """bench.timing on a tiny child: wall and CPU seconds, the three output modes, exit codes."""
    import sys

    from phonglab.bench import timing
    busy = ("import sys; s = sum(i * i for i in range(300000)); print('out'); "
            "print('err', file=sys.stderr)")
    run = timing.run_child([sys.executable, "-c", busy], capture=True)
    assert run.returncode == 0 and run.stdout == "out\n" and run.stderr == "err\n"
    assert run.seconds > 0 and 0 <= run.cpu_seconds <= run.seconds + 0.05
    log = tmp_path / "child.log"
    timing.run_child([sys.executable, "-c", busy], log=log)
    assert sorted(log.read_text().split()) == ["err", "out"]
    assert timing.run_child([sys.executable, "-c", "pass"], quiet=True).stdout is None
    fail = [sys.executable, "-c", "import sys; print('boom', file=sys.stderr); sys.exit(1)"]
    assert timing.run_child(fail, quiet=True, accept=(0, 1)).returncode == 1
    assert timing.run_child(fail, quiet=True, accept=None).returncode == 1
    with pytest.raises(timing.ChildFailed, match="exited 1:\nboom"):
        timing.run_child(fail, capture=True)
    with pytest.raises(timing.ChildFailed, match=f"exited 1; see {log}"):
        timing.run_child(fail, log=log)
    count = tmp_path / "count"
    tick = [sys.executable, "-c", f"open({str(count)!r}, 'a').write('.')"]
    runs = timing.run_repeated(tick, 3, warmup=2)
    assert len(runs) == 3 and count.read_text() == "....."


def test_timing_spread_median_range_values():
    from phonglab.bench.timing import spread
    assert spread([3.0, 1.0, 2.0, 10.0]) == {"median": 2.5, "spread": [1.0, 10.0],
                                            "values": [3.0, 1.0, 2.0, 10.0]}
    assert spread([0.12345, 0.5], 2) == {"median": 0.31, "spread": [0.12, 0.5],
                                         "values": [0.12, 0.5]}
    assert spread([1 / 3], None)["median"] == 1 / 3


def test_image_errors_remove_reference_noise():
    import numpy as np

    ref = np.full((4, 4, 3), 0.5)
    err = np.full((4, 4, 3), 0.1)
    img = ref + 0.2
    img[0, 0, 0] = np.nan
    e = errors(img, ref, err)
    assert e["nan_count"] == 1
    assert e["rmse"] == pytest.approx(math.sqrt(0.2 ** 2 - 0.1 ** 2))


def test_bench_cli_runs_resumes_and_reports(tmp_path, variant_llvm_rgb):
    out = tmp_path / "b"
    md = tmp_path / "B.md"
    args = ["bench", "--quick", "--out", str(out), "--only", "estimators", "--no-progress",
            "--markdown", str(md)]
    assert main(args) == 0
    rows = list(csv.DictReader((out / "results.csv").open()))
    cfg = bench.Config(quick=True)
    assert len(rows) == len(bench.ESTIMATOR_SCENES) * len(METHODS) * len(cfg.estimator_ns)
    assert all(r["nan_count"] == "0" and float(r["rmse"]) > 0 for r in rows)
    assert (out / "estimators.png").stat().st_size > 10_000
    # A second run resumes: no row is computed or written again.
    text = (out / "results.csv").read_text()
    assert main(args) == 0
    assert (out / "results.csv").read_text() == text
    report = md.read_text()
    assert "BSDF IS reaches uniform's error" in report and "estimators.png" in report
    assert json.loads((out / "run.json").read_text())["mode"] == "quick"


def test_bench_cli_rejects_unknown_part(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["bench", "--only", "everything"])
    assert exc.value.code == 2
    assert "invalid choice" in capsys.readouterr().err
