"""The contract topics of ``phonglab validate``: ``normalization`` (∫pdf = the probability
that sample() returns a counted direction), with analytic expectations for correct BSDFs and
the tolerance derived in phonglab.validate.bsdf.normalization."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from phonglab import stats
from phonglab.validate import validate_bsdf
from phonglab.validate.bsdf.normalization import counting_error


def _row(report, topic):
    (row,) = [r for r in report.rows if r.topic == topic]
    return row


def test_counting_error_without_rejection_leaves_z_squared_over_root_2_n():
    """k = N (nothing rejected): p̂(1 − p̂) = 0, yet the Agresti–Coull σ keeps
    z·σ ≈ z²/(√2 N) for a rejection not yet seen; at k = N/2 it is the binomial 0.5/√N."""
    n, z = 1 << 17, stats.z_critical(stats.ALPHA, 9)
    assert z * counting_error(np.array([n]), n, z)[0] == pytest.approx(z * z / (math.sqrt(2) * n),
                                                                      rel=1e-3)
    assert counting_error(np.array([n // 2]), n, z)[0] == pytest.approx(0.5 / math.sqrt(n),
                                                                       rel=1e-3)


def test_diffuse_normalization_is_one_lit_and_zero_at_grazing(variant_llvm_rgb):
    """diffuse: cosine sampling rejects nothing for cos θ_i > 0, so ∫pdf = P = 1 there, and
    Mitsuba rejects cos θ_i = 0 (diffuse.cpp: active &= cos_theta_i > 0), where both are 0."""
    row = _row(validate_bsdf("diffuse", quick=True, topics=["normalization"]), "normalization")
    assert row.status == "pass", row.reason
    d = row.details
    lit = np.cos(np.radians(d["theta_deg"])) > 1e-6
    assert np.allclose(np.array(d["integral"])[lit], 1.0, atol=1e-6)
    assert np.all(np.array(d["counted"])[lit] == 1.0)
    assert np.all(np.array(d["integral"])[~lit] == 0.0) and np.all(np.array(d["counted"])[~lit] == 0)
    # no rejection: the band is the quadrature's and the float32 floor (≤ 1e-4), not 1/√N
    assert max(d["band"]) < 1e-4


def test_plastic_is_held_to_its_non_delta_part(variant_llvm_rgb):
    """plastic = delta specular + diffuse: both Q and P are the diffuse lobe's probability
    (1 − the specular sampling probability), well below 1, and agree."""
    row = _row(validate_bsdf("plastic", quick=True, topics=["normalization"]), "normalization")
    assert row.status == "pass", row.reason
    q, p = np.array(row.details["integral"]), np.array(row.details["counted"])
    assert 0.1 < q.max() < 0.95 and np.all(np.abs(q - p) <= np.array(row.details["band"]))


def test_delta_only_bsdf_is_skipped(variant_llvm_rgb):
    row = _row(validate_bsdf("dielectric", quick=True, topics=["normalization"]), "normalization")
    assert row.status == "skipped" and "delta" in row.reason


def test_black_bsdf_counts_the_directions_it_draws(variant_llvm_rgb):
    """diffuse with reflectance 0: every weight is 0; the drawn directions (bs.pdf > 0 inside
    the support) are counted, P = 1 = ∫pdf."""
    row = _row(validate_bsdf("diffuse", params={"reflectance": 0.0}, quick=True,
                             topics=["normalization"]), "normalization")
    assert row.status == "pass", row.reason
    assert row.details["black_cells"] >= 3


def test_a_sampler_that_rejects_what_its_pdf_covers_fails(variant_llvm_rgb, tmp_path):
    """A Lambertian whose sample() marks every other direction rejected (weight 0) while pdf
    still integrates to 1: P = 1/2 against ∫pdf = 1."""
    src = (Path(__file__).parent / "defects" / "pdf_scaled_1pct.py").read_text()
    plugin = tmp_path / "half_rejected.py"
    plugin.write_text(src.replace("SCALE = 1.01", "SCALE = 1.0")
                      .replace("return bs, dr.select(bs.pdf > 0, value, 0.0)",
                               "return bs, dr.select((bs.pdf > 0) & (sample2.x < 0.5), value, 0.0)")
                      .replace("defect_pdf_scaled_1pct", "defect_half_rejected"))
    row = _row(validate_bsdf("defect_half_rejected", plugins=[plugin], quick=True,
                             topics=["normalization"]), "normalization")
    assert row.status == "fail"
    assert row.measured == pytest.approx(1.0, abs=1e-4)
    assert row.expected == pytest.approx(0.5, abs=0.01)
