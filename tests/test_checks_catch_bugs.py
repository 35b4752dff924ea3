"""The checks catch deliberately broken plugins: proof that the rows of `phonglab check` can fail.

Each broken variant subclasses a real plugin class (``registration.plugin_class``) and is
registered under another name; plugins/ is never edited.  Every test runs the relevant checks
on the broken plugin (Config.small()) and asserts which rows fail, and that the rows that
cannot see the mistake (by construction) still pass, so the failures are attributable.

* ``lambert_nopi``   eval drops the 1/π (f = ρ instead of ρ/π); sample() still returns ρ.
* ``phong_p1``       specular normalization (p+1)/(2π) instead of (p+2)/(2π) in f_r.
* ``phong_warped``   sample() draws from a distorted lobe (sample2.x → sample2.x²) while
                     pdf() and the weight keep the true density: sampling inconsistent with pdf.
* ``phong_badpdf``   pdf() uses (p+2)/(2π) for the sampling lobe, which draws with (p+1).
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

import phonglab
from phonglab import checks, probe, registration, runtime
from phonglab.engine import exr
from phonglab.cli import main

BROKEN = ("lambert_nopi", "phong_p1", "phong_warped", "phong_badpdf")


def _register_broken() -> None:
    lambert = registration.plugin_class("lambert", mi.variant())
    phong = registration.plugin_class("phong", mi.variant())

    class LambertNoPi(lambert):
        """f = ρ (the 1/π dropped) in eval/eval_pdf; sample() is the parent's (weight ρ)."""

        def eval(self, ctx, si, wo, active=True):
            active, cos_theta_o = self._active(ctx, si, wo, active)
            return dr.select(active, self.reflectance.eval(si, active) * cos_theta_o, 0.0)

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

    class _Rebroken(phong):
        """Re-applies ``_break`` after every (re)derivation of the parent's factors."""

        def __init__(self, props):
            super().__init__(props)
            self._break()

        def parameters_changed(self, keys=None):
            super().parameters_changed(keys)
            self._break()

    class PhongP1(_Rebroken):
        """The specular lobe normalized with (p+1)/(2π): albedo k_d + k_s (p+1)/(p+2) at θ_i = 0."""

        def _break(self):
            # Overrides the factor however the parent derives it (at load and after updates).
            self.brdf_factor = (self.exponent + 1.0) * dr.inv_two_pi

    class PhongWarped(phong):
        """sample() uses sample2.x² (a different distribution); pdf() is unchanged."""

        def sample(self, ctx, si, sample1, sample2, active=True):
            return super().sample(ctx, si, sample1, mi.Point2f(sample2.x * sample2.x, sample2.y),
                                  active)

    class PhongBadPdf(_Rebroken):
        """pdf() of the specular lobe with (p+2)/(2π): not the density sample() draws."""

        def _break(self):
            self.pdf_factor = (self.exponent + 2.0) * dr.inv_two_pi

    for name, cls in zip(BROKEN, (LambertNoPi, PhongP1, PhongWarped, PhongBadPdf)):
        mi.register_bsdf(name, lambda props, cls=cls: cls(props))


@pytest.fixture(scope="module")
def cfg(tmp_path_factory):
    phonglab.register("llvm_ad_rgb" if runtime.configure().usable else "scalar_rgb")
    _register_broken()
    return tmp_path_factory.mktemp("broken")


def _small(out_dir, **kw):
    return checks.Config.small(out_dir=out_dir, **kw)


def _failed(rows) -> set[str]:
    return {r.name for r in rows if r.status == "fail"}


def _passed(rows) -> set[str]:
    return {r.name for r in rows if r.status == "pass"}


def test_broken_variants_are_really_broken(cfg):
    # Guard against a subclass that silently changes nothing: evaluate one direction each.
    wi = probe.direction(np.radians([0.0]))
    wo = probe.direction(np.radians([30.0]))
    good = mi.load_dict(checks.gray("lambert", reflectance=0.5))
    bad = mi.load_dict(checks.gray("lambert_nopi", reflectance=0.5))
    assert probe.eval(bad, wi, wo)[0, 0] == pytest.approx(np.pi * probe.eval(good, wi, wo)[0, 0],
                                                          rel=1e-6)
    p = 30.0
    good = mi.load_dict(checks.phong_dict("phong", 0.0, 1.0, p))
    bad = mi.load_dict(checks.phong_dict("phong_p1", 0.0, 1.0, p))
    assert probe.eval(bad, wi, wi)[0, 0] == pytest.approx(
        probe.eval(good, wi, wi)[0, 0] * (p + 1) / (p + 2), rel=1e-6)
    bad = mi.load_dict(checks.phong_dict("phong_badpdf", 0.0, 1.0, p))
    assert probe.pdf(bad, wi, wi)[0] == pytest.approx(
        probe.pdf(good, wi, wi)[0] * (p + 2) / (p + 1), rel=1e-6)


def test_dropping_inv_pi_fails_energy_rows(cfg):
    rows = checks.check_energy(_small(cfg, lambert="lambert_nopi"))
    failed = _failed(rows)
    for name in ("lambert_nopi: furnace, eval/cos-pdf", "lambert_nopi: furnace render, path (MIS)",
                 "lambert_nopi: cube enclosure ρ=0.5", "lambert_nopi: cube enclosure ρ=1 D=5",
                 "lambert_nopi: sphere, emitter only"):
        assert name in failed, name
    # Rows that use only sample() (weight ρ, by construction) cannot see the missing 1/π,
    # and the built-in diffuse rows are untouched: the failures point at eval.
    passed = _passed(rows)
    assert "lambert_nopi: furnace, sample weight" in passed
    assert "lambert_nopi: furnace render, BSDF only" in passed
    assert {r.name for r in rows if r.name.startswith("diffuse") and "sphere" not in r.name} <= passed


def test_dropping_inv_pi_fails_reflection_scene_constancy_and_sanity_rows(cfg):
    c = _small(cfg, lambert="lambert_nopi")
    refl = checks.check_reflection(c)
    assert {"lambert_nopi: quadrature", "lambert_nopi ρ=0.7: render θ_r=60°"} <= _failed(refl)
    assert "phong p=0: normal incidence" in _passed(refl)

    scene = checks.check_scene(c)
    assert _failed(scene) == {r.name for r in scene}       # per-pixel test and mean difference
    diff_path = scene[0].details["difference_image"]
    diff, meta = exr.read(diff_path)
    assert meta["what"] == "lambert − diffuse" and float(np.mean(diff)) > 0.1

    const = checks.check_constancy(c)
    failed = _failed(const)
    assert {f"lambert_nopi probe r={r:g}" for r in checks.DISTANCES} <= failed
    assert {f"lambert_nopi plane d={d:g}" for d in checks.DISTANCES} <= failed
    assert "emitter d=1000" in _passed(const)              # no lambert involved

    sanity = checks.check_sanity(c)
    assert "lambert_nopi: weight = eval/pdf" in _failed(sanity)
    assert "lambert_nopi: reciprocity" in _passed(sanity)  # ρ is still symmetric


def test_p_plus_one_normalization_fails_normal_incidence_rows(cfg):
    rows = checks.check_reflection(_small(cfg, phong="phong_p1"))
    failed = _failed(rows)
    # k_s/(p+2) = 0.5/(p+2) missing: far beyond the 1e-5 budget up to p = 1000.
    for p in (0, 1, 10, 100, 1000):
        assert f"phong_p1 p={p}: normal incidence" in failed, p
    # eval, pdf and sample() stay mutually consistent, so Monte Carlo agrees with quadrature:
    # only the analytic k_d + k_s exposes the normalization.
    assert "phong_p1 p=30: render θ_r=0°" in _passed(rows)
    assert all(f"phong_p1 p={p:g}: sample() vs quadrature" in _passed(rows)
               for p in checks.EXPONENTS)


def test_sampling_inconsistent_with_pdf_fails_chi2_and_monte_carlo_rows(cfg):
    c = _small(cfg, phong="phong_warped")
    sanity = checks.check_sanity(c)
    failed = _failed(sanity)
    for p in ("0", "30", "300"):
        assert f"phong_warped p={p}: χ² sampling" in failed, p
    assert "lambert: χ² sampling" in _passed(sanity)
    refl = checks.check_reflection(c)
    for p in (0, 1, 10, 100, 1000):
        assert f"phong_warped p={p}: sample() vs quadrature" in _failed(refl), p
    assert "phong_warped p=30: render θ_r=60°" in _failed(refl)


def test_pdf_with_wrong_normalization_fails_chi2_and_monte_carlo_rows(cfg):
    c = _small(cfg, phong="phong_badpdf")
    sanity = checks.check_sanity(c)
    # p = 0: the specular pdf is twice the sampled density, χ² rejects.  At p = 30 the lobe's
    # pdf is off by 1/(p+1) = 3 % of one mixture component, below what χ² resolves with 65536
    # samples; the Monte Carlo rows below catch it because the weight is eval/pdf.
    assert "phong_badpdf p=0: χ² sampling" in _failed(sanity)
    refl = checks.check_reflection(c)
    for p in (0, 1, 10, 100, 1000):
        assert f"phong_badpdf p={p}: sample() vs quadrature" in _failed(refl), p
    # eval is intact: the analytic normal-incidence rows still pass.
    assert "phong_badpdf p=0: normal incidence" in _passed(refl)


def test_cli_exits_nonzero_and_names_the_failing_rows(cfg, capsys):
    code = main(["check", "--only", "reflection", "--phong", "phong_p1", "--spp", "16",
                 "--no-progress", "--out-dir", str(cfg)])
    out = capsys.readouterr().out
    assert code == 1
    assert "fail reflection/phong_p1 p=0: normal incidence" in out
