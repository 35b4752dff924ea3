"""The validator catches each planted defect in its own topic and in no other; correct BSDFs pass.

The defects are tests/defects/*.py, BSDF plugins written as an author would (they register
themselves with mi.register_bsdf), each with one planted mistake (see tests/defects/README.md).
Quick mode and a fixed seed: the statistical topics (chi2, energy) are run at the family-wise
level ALPHA = 0.01 (Šidák over the BSDF's tests), so a correct plugin fails a run with
probability ≤ 1 %; the defects are off by far more than the tolerances (a factor of π in
energy, 2·u per sample in weight, ...), so they fail with probability ≈ 1.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from phonglab.validate import validate_bsdf
from phonglab.validate.bsdf.topics import TOPICS

DEFECTS = Path(__file__).parent / "defects"

#: defect file -> the one topic it must fail
PLANTED = {
    "energy_gain": "energy",
    "weight_noise": "weight",
    "pdf_mismatch": "chi2",
    "nonreciprocal": "reciprocity",
    "nan_grazing": "finite",
    "stale_sample_pdf": "pdf",
    "eval_pdf_mismatch": "eval_pdf",
    "swapped_components": "component",
    "wrong_gradient": "gradient",
    "pdf_scaled_1pct": "normalization",
    "pdf_scaled_2pct": "normalization",
    "null_transmission_without_lobe": "eval_null_transmission",
    "null_transmission_wrong": "eval_null_transmission",
    "diffuse_reflectance_no_pi": "eval_diffuse_reflectance",
    "undeclared_lobe": "component",
    "lit_from_below": "component",
}

#: defect file -> topics that may fail besides its own at DEFAULT sizes, and why.  A pdf scaled
#: by 1.02 adds ≈ N·0.02² = 400 to the χ² statistic at N = 10⁶ samples, 2σ of its null
#: distribution (σ = √(2·dof) ≈ 200): χ² may see it then; its default-size counterpart, the
#: 1 % defect (excess 100, σ/2), fails normalization alone.
#: lit_from_below's pdf (no cos θ_i test) integrates to 1 at exactly grazing incidence, where its
#: sample() refuses: the default sizes' θ_i = 90° cells see the same defect as normalization
ALSO_AT_DEFAULT = {"pdf_scaled_2pct": {"chi2"}, "lit_from_below": {"normalization"}}


@pytest.mark.parametrize("name", sorted(PLANTED))
def test_defect_fails_its_topic_only(variant_llvm_rgb, name):
    report = validate_bsdf(f"defect_{name}", plugins=[DEFECTS / f"{name}.py"], quick=True, seed=0)
    failing = {r.topic for r in report.failing}
    assert failing == {PLANTED[name]}, report.table(report.failing)


def test_pdf_scaled_1pct_fails_normalization_alone_at_default_sizes(variant_llvm_rgb):
    """A pdf 1 % too large fails at default sizes: ∫pdf = 1.01 against P = 1 (no rejection),
    a band of z²/(√2 N) + the quadrature's error, ~3e-5."""
    report = validate_bsdf("defect_pdf_scaled_1pct", plugins=[DEFECTS / "pdf_scaled_1pct.py"],
                           seed=0)
    assert {r.topic for r in report.failing} == {"normalization"}, report.table(report.failing)
    (row,) = [r for r in report.rows if r.topic == "normalization"]
    assert row.measured == pytest.approx(1.01, abs=1e-6) and row.expected == 1.0
    assert row.tolerance < 1e-4


@pytest.mark.slow
@pytest.mark.parametrize("name", ["pdf_scaled_2pct", "lit_from_below"])
def test_normalization_defects_fail_it_at_default_sizes(variant_llvm_rgb, name):
    """The other planted defects that fail ``normalization`` today (pdf_scaled_1pct has its own
    test above; at --quick the 1 % and 2 % ones fail it in test_defect_fails_its_topic_only)
    fail it at default sizes too, a BSDF's lobes being placed one by one."""
    report = validate_bsdf(f"defect_{name}", plugins=[DEFECTS / f"{name}.py"], seed=0,
                           topics=["normalization"])
    assert {r.topic for r in report.failing} == {"normalization"}, report.table(report.rows)


def test_failing_chi2_writes_nothing_into_the_working_directory(variant_llvm_rgb, tmp_path,
                                                                monkeypatch):
    # mi.chi2 dumps chi2_data.py on a failed test unless quiet; the own χ² test writes nothing
    monkeypatch.chdir(tmp_path)
    report = validate_bsdf("defect_pdf_mismatch", plugins=[DEFECTS / "pdf_mismatch.py"],
                           quick=True, seed=0, topics=["chi2"])
    assert {r.topic for r in report.failing} == {"chi2"}
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("bsdf", ["diffuse", "lambert", "phong"])
def test_correct_bsdfs_pass_quick(variant_llvm_rgb, bsdf):
    report = validate_bsdf(bsdf, quick=True, seed=0)
    assert report.passed, report.table(report.failing)
    assert {r.topic for r in report.rows} == set(TOPICS)


def test_every_topic_but_cost_has_a_planted_defect():
    """Here or, for the topics of polarized variants, in tests/defects_polarized."""
    from test_validate_polarized import PLANTED as POLARIZED_PLANTED

    assert set(PLANTED.values()) | set(POLARIZED_PLANTED.values()) | {"cost"} == set(TOPICS)


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(PLANTED))
def test_defect_fails_its_topic_only_default_sizes(variant_llvm_rgb, name):
    report = validate_bsdf(f"defect_{name}", plugins=[DEFECTS / f"{name}.py"], seed=0)
    failing = {r.topic for r in report.failing}
    assert PLANTED[name] in failing, report.table(report.failing)
    assert failing <= {PLANTED[name]} | ALSO_AT_DEFAULT.get(name, set()), report.table(report.failing)


@pytest.mark.slow
@pytest.mark.parametrize("bsdf", ["diffuse", "lambert", "phong"])
def test_correct_bsdfs_pass_default_sizes(variant_llvm_rgb, bsdf):
    report = validate_bsdf(bsdf, seed=0)
    assert report.passed, report.table(report.failing)


@pytest.mark.slow
def test_false_failure_rate_quick(variant_llvm_rgb):
    """lambert and phong (independent samplers) over 20 seeds each, quick sizes: 40 runs that
    each fail with probability ≤ ALPHA = 0.01; P(≥ 3 failures) = 0.0075 < ALPHA, so ≥ 3 fails."""
    from scipy import stats as scipy_stats

    from phonglab import stats
    from phonglab.validate.batch import false_failures
    result = false_failures(["lambert", "phong"], 20, quick=True, kind="bsdf")
    count = sum(bool(failing) for runs in result.values() for _, failing in runs)
    assert scipy_stats.binom.sf(2, 40, stats.ALPHA) < stats.ALPHA
    assert count <= 2, result
