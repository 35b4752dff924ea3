"""``validate --profile`` and ``meta["profile"]``: where a run's time went, per topic and per
sweep point (phonglab.validate.profile)."""

from __future__ import annotations

from phonglab.cli import main
from phonglab.validate import profile, validate_bsdf


def test_every_topic_run_has_its_time_split_and_the_parts_add_up(variant_llvm_rgb):
    report = validate_bsdf("diffuse", quick=True, topics=["finite", "chi2"])
    prof = report.meta["profile"]
    assert set(prof) == {"finite", "chi2"}
    for r in prof.values():
        assert set(r) == set(profile.FIELDS)
        assert r["kernels"] >= 1 and 0 <= r["compiled"] <= r["kernels"]
        assert abs(r["compile_s"] + r["execute_s"] + r["other_s"] - r["seconds"]) < 2e-3 \
            or r["other_s"] == 0.0


def test_a_sweep_sums_its_points_per_topic_and_keeps_each_points_total(variant_llvm_rgb):
    report = validate_bsdf("diffuse", quick=True, topics=["finite"], sweep=True)
    runs = [r for r in report.meta["sweep"]["runs"] if r["status"] == "run"]
    assert len(runs) >= 2 and all("profile" in r for r in runs)
    summed = sum(r["profile"]["kernels"] for r in runs)
    assert report.meta["profile"]["finite"]["kernels"] == summed


def test_the_cli_prints_the_profile(variant_llvm_rgb, capsys):
    assert main(["validate", "diffuse", "--quick", "--only", "finite", "--profile"]) == 0
    out = capsys.readouterr().out
    assert "where the time went" in out and "per sweep point:" in out
    assert "finite" in out.split("where the time went")[1]
