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


def test_chi2_counts_a_sample_whose_weight_is_0_because_the_bsdf_is_black_there(
        variant_llvm_rgb):
    """plastic at int_ior 1 (η = 0.99972, the sweep's corner), default sizes: diffuse samples
    beyond the critical angle (cos θ_o < 0.0236) have eval 0 and weight 0. χ² dropped them
    while pdf counts that region, so the first cos θ_o row was empty (p = 3.5e-13); they
    count, as in the normalization topic (lanes.black_at_wo)."""
    report = validate_bsdf({"type": "plastic", "int_ior": 1.0}, topics=["chi2"])
    row = _row(report, "chi2")
    assert row.status == "pass", row.reason


def test_a_spike_beside_a_broad_lobe_is_integrated(variant_llvm_rgb):
    """principled with every parameter 1 (a sweep corner) at cos θ_i = 1e-4: ~1 % of the
    samples fall in a clearcoat spike ~7e-4 rad wide beside a GGX lobe 0.3 rad wide. A rule
    of the broad lobe's width gives ∫pdf 0.8625 for 0.9004 counted (a fail; independent Monte
    Carlo: 0.905 ± 0.0015); the layout centres the rule on the spike."""
    import mitsuba as mi

    from phonglab.validate.bsdf import lobes
    spec = {"type": "principled", **dict.fromkeys(
        ("base_color", "metallic", "specular", "spec_tint", "anisotropic", "sheen",
         "sheen_tint", "clearcoat", "clearcoat_gloss", "spec_trans", "roughness"), 1.0)}
    row = _row(validate_bsdf(spec, quick=True, topics=["normalization"]), "normalization")
    assert row.status == "pass", row.reason
    grazing = np.cos(np.radians(row.details["theta_deg"])) < 1e-3
    assert np.allclose(np.array(row.details["integral"])[grazing],
                       np.array(row.details["counted"])[grazing], atol=0.005)
    cells = np.array([[math.acos(1e-4), 0.0], [math.acos(1e-4), 2.1]])
    for reflected, _ in lobes.layout(mi.load_dict(spec), cells, seed=0):
        assert reflected[2] < 1e-3                  # the spike's width, not the lobe's 0.3


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
    the support, where eval is 0) are counted, P = 1 = ∫pdf at every lit cell."""
    row = _row(validate_bsdf("diffuse", params={"reflectance": 0.0}, quick=True,
                             topics=["normalization"]), "normalization")
    assert row.status == "pass", row.reason
    lit = np.cos(np.radians(row.details["theta_deg"])) > 1e-6
    n = row.details["samples"]
    assert all(b == n for b, x in zip(row.details["black_samples"], lit) if x)
    assert np.all(np.array(row.details["counted"])[lit] == 1.0)


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


# ----------------------------------------------------------------------------- contract topics
def _cutout(tmp_path) -> Path:
    """The correct cut-out Lambertian: tests/defects/null_transmission_wrong.py with its
    eval_null_transmission fixed to 1 − opacity."""
    src = (Path(__file__).parent / "defects" / "null_transmission_wrong.py").read_text()
    fixed = src.replace("return mi.Spectrum(self.opacity)  ", "return mi.Spectrum(1.0 - self.opacity)  ")
    assert fixed != src
    plugin = tmp_path / "cutout.py"
    plugin.write_text(fixed.replace("defect_null_transmission_wrong", "cutout"))
    return plugin


def test_a_correct_cutout_passes_every_topic(variant_llvm_rgb, tmp_path):
    """Opacity 0.3: the Null lobe passes 1 − 0.3 = 0.7 along −wi, which sample() (Null-only
    context: weight 0.7, pdf 1) and eval_null_transmission agree on; its diffuse part is
    Lambertian, and the inherited eval_diffuse_reflectance π·eval(wi, n) = 0.3·ρ is exact."""
    report = validate_bsdf("cutout", plugins=[_cutout(tmp_path)], quick=True)
    assert report.passed, report.table(report.failing)
    (null, direction) = [r for r in report.rows if r.topic == "eval_null_transmission"]
    assert null.measured == pytest.approx(0.7, rel=1e-6)
    assert np.allclose(null.details["sampled"], 0.7, rtol=1e-6)
    assert direction.status == "pass"
    edr = _row(report, "eval_diffuse_reflectance")
    assert edr.status == "pass" and edr.measured == pytest.approx(0.15, rel=1e-6)


@pytest.mark.parametrize("spec, expected", [
    ({"type": "thindielectric"}, None),
    ({"type": "null"}, 1.0),
    ({"type": "mask", "opacity": 0.3, "bsdf": {"type": "diffuse"}}, 0.7),
    ({"type": "blendbsdf", "weight": 0.3, "bsdf_0": {"type": "null"},
      "bsdf_1": {"type": "diffuse"}}, 0.7),
], ids=["thindielectric", "null", "mask", "blendbsdf"])
def test_builtin_null_lobes_agree_with_their_samples(variant_llvm_rgb, spec, expected):
    """thindielectric: 1 − r' with r' = 2r/(1 + r), the same value as its Null-only sample's
    weight (thindielectric.cpp:164-173, :203-217); null: 1; mask: 1 − opacity; blendbsdf of
    null and diffuse at weight 0.3: 0.7 (the tolerance: z·stderr of a Bernoulli mean)."""
    report = validate_bsdf(spec, quick=True, topics=["eval_null_transmission"])
    assert report.passed, report.table(report.failing)
    row = report.rows[0]
    if expected is not None:
        assert row.measured == pytest.approx(expected, rel=1e-6)


def test_bsdfs_without_a_null_lobe_return_zero(variant_llvm_rgb):
    for spec in ("diffuse", "roughplastic", "conductor"):
        row = _row(validate_bsdf(spec, quick=True, topics=["eval_null_transmission"]),
                   "eval_null_transmission")
        assert row.status == "pass" and row.measured == 0.0, (spec, row.reason)


def test_lambertian_diffuse_reflectance_is_its_albedo(variant_llvm_rgb):
    """diffuse, lambert, twosided(diffuse): ρ = ∫ ρ/π cos θ_o dω_o = 0.5 at every lit cell."""
    for spec in ("diffuse", "lambert", {"type": "twosided", "bsdf": {"type": "diffuse"}}):
        row = _row(validate_bsdf(spec, quick=True, topics=["eval_diffuse_reflectance"]),
                   "eval_diffuse_reflectance")
        assert row.status == "pass", row.reason
        assert np.allclose(row.details["diffuse_albedo"], 0.5, atol=1e-6)


def test_fresnel_weighted_diffuse_lobes_are_not_held_to_it(variant_llvm_rgb):
    """plastic and roughplastic return their diffuse_reflectance parameter for a lobe that
    reflects ρ t_i t_o / (η²(1 − ρ F_dr)) / π: not Lambertian, Mitsuba documents an
    approximation (bsdf.h:566-575), so the row is skipped with the ratio."""
    for spec in ("plastic", "roughplastic"):
        row = _row(validate_bsdf(spec, quick=True, topics=["eval_diffuse_reflectance"]),
                   "eval_diffuse_reflectance")
        assert row.status == "skipped" and "not Lambertian" in row.reason, row.reason
        assert not any(row.details["lambertian"])


def test_a_lobe_that_vanishes_at_some_incidences_only_is_not_lambertian_there(variant_llvm_rgb):
    """plastic at int_ior 1 (η = 1/1.000277 < 1, the BSDF sweep's corner): beyond the critical
    angle its coating reflects everything, so the diffuse lobe is 0 at cos θ_i = 1e-4 and
    eval_diffuse_reflectance is still ρ = 0.5. A lobe that is 0 there and not elsewhere
    depends on ω_i: not Lambertian (the row was a fail, 0.5 vs 0). A lobe that is 0
    everywhere (diffuse, ρ = 0) is still held to its albedo 0."""
    row = _row(validate_bsdf({"type": "plastic", "int_ior": 1.0}, quick=True,
                             topics=["eval_diffuse_reflectance"]), "eval_diffuse_reflectance")
    assert row.status == "skipped" and "not Lambertian" in row.reason, row.reason
    assert min(row.details["diffuse_albedo"]) == 0.0 and max(row.details["value"]) == 0.5
    row = _row(validate_bsdf({"type": "diffuse", "reflectance": 0.0}, quick=True,
                             topics=["eval_diffuse_reflectance"]), "eval_diffuse_reflectance")
    assert row.status == "pass" and all(row.details["lambertian"]), row.reason


def test_the_inherited_default_approximation_passes_with_a_note(variant_llvm_rgb):
    """blendbsdf(diffuse 0.7, roughconductor 0.3) blends roughconductor's inherited default
    π·eval(wi, n) (bsdf.cpp:38-43): 7.85 at normal incidence, where the mirror peak lies at n,
    for a diffuse albedo of 0.35. It is Mitsuba's documented approximation: a note, no fail."""
    spec = {"type": "blendbsdf", "weight": 0.3, "bsdf_0": {"type": "diffuse"},
            "bsdf_1": {"type": "roughconductor"}}
    row = _row(validate_bsdf(spec, quick=True, topics=["eval_diffuse_reflectance"]),
               "eval_diffuse_reflectance")
    assert row.status == "pass" and "documented approximation" in row.reason, row.reason
    assert max(row.details["value"]) > 7.0


def test_mask_reports_its_nested_reflectance_without_the_opacity(variant_llvm_rgb):
    """A Mitsuba 3.9.1 finding: mask.cpp:229-231 returns the nested BSDF's diffuse
    reflectance (0.5) while its eval scales the nested eval by the opacity (albedo 0.25 at
    opacity 0.5), and π·eval(wi, n) is 0.25 too: neither the albedo nor the default."""
    row = _row(validate_bsdf({"type": "mask", "bsdf": {"type": "diffuse"}}, quick=True,
                             topics=["eval_diffuse_reflectance"]), "eval_diffuse_reflectance")
    assert row.status == "fail"
    assert row.measured == pytest.approx(0.5) and row.expected == pytest.approx(0.25, rel=1e-6)


# ----------------------------------------------------------------------------- component lies
def _variant_of(tmp_path, defect: str, name: str, *edits) -> Path:
    """tests/defects/<defect>.py with the text edits applied, registered as ``name``."""
    src = (Path(__file__).parent / "defects" / f"{defect}.py").read_text()
    out = src
    for old, new in edits:
        assert old in out, old
        out = out.replace(old, new)
    plugin = tmp_path / f"{name}.py"
    plugin.write_text(out.replace(f"defect_{defect}", name))
    return plugin


def _failing_component_rows(name, plugin):
    report = validate_bsdf(name, plugins=[plugin], quick=True, topics=["component"])
    return {r.name for r in report.rows if r.status == "fail"}


def test_a_glossy_lobe_outside_the_declared_flags_is_caught(variant_llvm_rgb, tmp_path):
    """component_count() = 1 and flags DiffuseReflection, but glossy samples reported as
    GlossyReflection of component 0: a sampled_type outside flags(0)."""
    plugin = _variant_of(tmp_path, "undeclared_lobe", "glossy_outside_flags",
                         ("mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.GlossyReflection\n"
                          "                             | mi.BSDFFlags.FrontSide",
                          "mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide"))
    assert _failing_component_rows("glossy_outside_flags", plugin) == {
        "sampled_component/sampled_type agree with the flags", "one sampled_type per component"}


def test_flags_that_are_not_the_union_of_the_components_are_caught(variant_llvm_rgb, tmp_path):
    """A Lambertian whose flags() says DeltaReflection (path.cpp:238 would then never sample
    emitters for it) while its one component is DiffuseReflection."""
    plugin = _variant_of(tmp_path, "pdf_scaled_1pct", "flags_lie",
                         ("SCALE = 1.01", "SCALE = 1.0"),
                         ("self.m_flags = self.m_components[0]",
                          "self.m_flags = mi.BSDFFlags.DeltaReflection | mi.BSDFFlags.FrontSide"))
    assert _failing_component_rows("flags_lie", plugin) == {"flags() = union of flags(k)"}


def test_a_delta_lobe_labelled_diffuse_is_an_atom(variant_llvm_rgb, tmp_path):
    """A Lambertian that sends 30 % of its samples exactly to reflect(wi), labelled
    DiffuseReflection: ~30 % of each lit cell's samples share one direction, which a density
    draws with probability 0 (χ² and normalization see it too; this row names it)."""
    plugin = _variant_of(tmp_path, "pdf_scaled_1pct", "delta_as_diffuse",
                         ("SCALE = 1.01", "SCALE = 1.0"),
                         ("bs.wo = mi.warp.square_to_cosine_hemisphere(sample2)",
                          "bs.wo = dr.select(sample1 < 0.3, mi.reflect(si.wi),\n"
                          "                          mi.warp.square_to_cosine_hemisphere(sample2))"))
    assert _failing_component_rows("delta_as_diffuse", plugin) == {
        "non-delta samples have a density (no atom)"}


def test_correct_multi_lobe_bsdfs_keep_one_type_per_component(variant_llvm_rgb):
    """phong [diffuse, glossy], plastic [delta, diffuse], roughdielectric [R, T]: one
    sampled_type per component, flags() the union, no atom."""
    for spec in ("phong", "plastic", "roughdielectric"):
        report = validate_bsdf(spec, quick=True, topics=["component"])
        assert report.passed, report.table(report.failing)
