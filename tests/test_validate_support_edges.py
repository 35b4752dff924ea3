"""Rules of the BSDF validator that a re-run of the conformance table put to the test.

``normalization``: a support that ends short of the horizon.  roughdielectric's transmitted
pdf at grazing incidence ends at |ω_z| = cos θ_i / η (refraction through microfacets
perpendicular to the surface) with a jump there (pdf ≈ 1.6 on the lobe's side, 0 between it
and the horizon).  A rule whose last panel runs on to the horizon integrated it (GGX α 0.3,
η 1.504, cos θ_i = 1e-4, φ_i = 2.1) to 1.0000595, 1.0000563, 1.0000510, 1.0000454, 1.0000404,
0.9999626 with 8, 12, 16, 32, 64, 96 nodes per panel -- the float64 formula at the same nodes
within 2e-8 of each -- against a count of 1 (all of 2¹⁹ samples valid): |Q16 − Q8| = 2.2e-5
hid an error of 5.1e-5.  At cos θ_i = 0.01 the rules scattered by 1e-3 (band 6.8e-3).  The
validator now ends a panel at the smallest |ω_z| of each group of counted samples per
hemisphere where pdf is 0 halfway to the horizon (``lobes.support_heights``,
``lobe_quadrature``'s ``heights``).

``component``: a sample with a NaN weight is the ``finite`` topic's, not one that reports a
lobe: blendbsdf of roughconductor and roughdielectric at cos θ_i = 0 turns a sample that
roughdielectric rejected (weight 0, labelled GlossyTransmission) into weight NaN
(blendbsdf.cpp:151, the finding blendbsdf-nan-weight), which the type_mask row counted as a
glossy transmission sample asked for by a GlossyReflection mask (2460 samples, all at
cos θ_i = 0; ``lanes.drawn`` now leaves them out).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from phonglab.physics.quadrature import lobe_quadrature
from phonglab.validate import validate_bsdf


@pytest.mark.parametrize("theta,azimuth", [(0.0, math.pi), (0.3, 1.0), (1.2, 4.0),
                                           (1.45, math.pi)])
def test_a_height_edge_integrates_a_jump_parallel_to_the_horizon(theta, azimuth):
    """1{ω_z > h} integrates to 2π(1 − h) to round-off with h an edge of every φ node (the
    rule's centre above h); without it the panel that runs on to the horizon misses ~h."""
    for h in [h for h in (6.6e-5, 0.01, 0.3) if h < math.cos(theta)]:
        exact = 2 * math.pi * (1 - h)
        wo, w = lobe_quadrature(theta, 0.05, 8, azimuth=azimuth, symmetric=False,
                                heights=(h, 1e-3))
        z = wo[:, 2] / np.linalg.norm(wo, axis=1)
        assert np.sum(w) == pytest.approx(2 * math.pi, rel=1e-12)
        assert np.sum(w * (z > h)) == pytest.approx(exact, rel=1e-12)
        wo, w = lobe_quadrature(theta, 0.05, 8, azimuth=azimuth, symmetric=False)
        z = wo[:, 2] / np.linalg.norm(wo, axis=1)
        assert abs(np.sum(w * (z > h)) / exact - 1) > 1e-3 * h


def test_roughdielectric_pdf_integrates_at_grazing_incidence(variant_llvm_rgb):
    """GGX α 0.3: every cell within its band, the quadrature error at cos θ_i = 0.01 and 1e-4
    below 1e-4 (it was 6.8e-3 and 2.2e-5 with an error of 5.1e-5), and ∫pdf there within
    3e-5 of the count."""
    report = validate_bsdf({"type": "roughdielectric", "distribution": "ggx", "alpha": 0.3},
                           topics=["normalization"], seed=0)
    (row,) = [r for r in report.rows if r.topic == "normalization"]
    assert row.status == "pass", row.reason
    d = row.details
    cos = np.cos(np.radians(d["theta_deg"]))
    grazing = (cos > 1e-5) & (cos < 0.02)
    assert grazing.sum() == 4
    assert np.max(np.array(d["quadrature_error"])[grazing]) < 1e-4
    gap = np.abs(np.array(d["integral"]) - np.array(d["counted"]))[grazing]
    assert np.max(gap) < 3e-5 + 3 * np.max(np.array(d["sigma"])[grazing]), gap


def test_a_nan_sample_reports_no_lobe_in_the_component_rows(variant_llvm_rgb):
    """blendbsdf's NaN samples at cos θ_i = 0 are left out of the type_mask row and counted in
    its details; the row passes."""
    spec = {"type": "blendbsdf", "weight": 0.6,
            "bsdf_0": {"type": "roughconductor", "alpha": 0.3},
            "bsdf_1": {"type": "roughdielectric", "alpha": 0.2}}
    report = validate_bsdf(spec, topics=["component"], seed=0)
    (row,) = [r for r in report.rows if r.name == "type_mask: samples only the lobes asked for"]
    assert row.status == "pass", row.reason
    assert row.details["nonfinite"] > 0
