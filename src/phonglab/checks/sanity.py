r"""Check 6, ``sanity``: reciprocity, non-negativity/finiteness, weight = eval/pdf and χ², per plugin.

* Reciprocity: f(ω_i, ω_o) = eval(ω_i → ω_o)/cos θ_o equals f(ω_o, ω_i); the relative
  difference over random pairs (both above the surface, incl. grazing ones) must stay within
  the float32 budget 32·2⁻²⁴·(p + 1): cos α = ω_o·R(ω_i) is rounded differently in the two
  orders, and cos^p α amplifies a relative error by p.
* Non-negativity and finiteness of eval, pdf and sample weight over random directions on the
  whole sphere (below the horizon included) and grazing ones (|cos θ| down to 1e-7):
  the number of negative or non-finite values must be 0.
* weight = eval/pdf at the sampled directions, relative budget 64·2⁻²⁴.
* χ² test of sample() against pdf() (``mi.chi2.ChiSquareTest``, ``BSDFAdapter``) at
  θ_i ∈ {0°, 45°, 80°}; its p-value must exceed the Šidák level of all χ² tests of this check,
  and the histogram must not be empty (an empty one passes vacuously).  The expected cell
  counts integrate pdf() with 16 x 16 trapezoid points per cell (``ires=16``): with the
  default 4 x 4 a p = 300 lobe at normal incidence, narrower than one cos θ row of the
  101-row grid, is integrated too coarsely and the test rejects a correct sampler.
"""

from __future__ import annotations

import math

import mitsuba as mi
import numpy as np

from .. import probe, registration, stats
from .common import EPS32, CheckResult, Config, Rows, gray, phong_dict

#: Incidence angles (degrees) of the χ² tests.
CHI2_ANGLES = (0.0, 45.0, 80.0)


def check_sanity(cfg: Config) -> list[CheckResult]:
    """Reciprocity, non-negativity/finiteness, weight = eval/pdf and χ² for every case."""
    registration.register()
    rows = Rows("sanity")
    cases = _sanity_cases(cfg)
    n = max(4096, cfg.samples // 4)
    chi2_tests = len(cases) * len(CHI2_ANGLES)
    for k, (label, spec, p) in enumerate(cases):
        cfg.note(f"sanity: {label}")
        bsdf = mi.load_dict(spec)
        rng = cfg.rng(600 + k)
        _reciprocity(rows, label, bsdf, p, rng, n)
        _values_and_weights(rows, label, bsdf, rng, n)
        _chi2(cfg, rows, label, spec, k, chi2_tests)
    return rows.finish()


def _sanity_cases(cfg: Config) -> list[tuple[str, dict, float]]:
    """(label, plugin dict, exponent p for the float budget)."""
    cases = [(f"{cfg.lambert}", gray(cfg.lambert, reflectance=0.7), 0.0),
             ("diffuse", gray("diffuse", reflectance=0.7), 0.0)]
    for p in (0.0, 30.0, 300.0):
        cases.append((f"{cfg.phong} p={p:g}", phong_dict(cfg.phong, 0.4, 0.5, p), p))
    return cases


def _random_dirs(rng, n: int, grazing: int) -> np.ndarray:
    """Uniform directions on the sphere plus ``grazing`` ones with |cos θ| in [1e-7, 1e-2]."""
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    phi = rng.uniform(0, 2 * np.pi, grazing)
    cz = 10.0 ** rng.uniform(-7, -2, grazing) * rng.choice([-1.0, 1.0], grazing)
    s = np.sqrt(1 - cz * cz)
    g = np.stack([s * np.cos(phi), s * np.sin(phi), cz], axis=1)
    return np.concatenate([d, g])


def _reciprocity(rows: Rows, label: str, bsdf, p: float, rng, n: int) -> None:
    up = _random_dirs(rng, n, n // 8)
    up[:, 2] = np.abs(up[:, 2])
    up2 = _random_dirs(rng, n, n // 8)
    up2[:, 2] = np.abs(up2[:, 2])
    f_io = probe.eval(bsdf, up, up2)[:, 0] / up2[:, 2]
    f_oi = probe.eval(bsdf, up2, up)[:, 0] / up[:, 2]
    scale = np.maximum(np.abs(f_io), np.abs(f_oi))
    rel = np.where(scale > 0, np.abs(f_io - f_oi) / np.where(scale > 0, scale, 1.0), 0.0)
    rows.exact(f"{label}: reciprocity", f"{label}: max relative |f(ωi,ωo) − f(ωo,ωi)| "
               f"({len(up)} pairs, grazing incl.)", float(rel.max()), 0.0,
               "Helmholtz reciprocity", 32 * EPS32 * (p + 1))


def _values_and_weights(rows: Rows, label: str, bsdf, rng, n: int) -> None:
    """Non-negative, finite eval/pdf/sample over the whole sphere; weight = eval/pdf."""
    wi = _random_dirs(rng, n, n // 8)
    wo = _random_dirs(rng, n, n // 8)
    ev, pd = probe.eval(bsdf, wi, wo)[:, 0], probe.pdf(bsdf, wi, wo)
    u = rng.random((len(wi), 3))
    s = probe.sample(bsdf, wi, u[:, 0], u[:, 1:])
    swo, spdf, sw = s.wo, s.pdf, s.weight[:, 0]
    values = np.concatenate([ev, pd, sw, spdf])
    bad = int(np.sum(~np.isfinite(values)) + np.sum(values < 0)
              + np.sum(~np.isfinite(swo)))
    rows.exact(f"{label}: non-negative, finite", f"{label}: negative or non-finite eval/pdf/"
               f"sample values ({len(values)}, whole sphere + grazing)", bad, 0,
               "f_r >= 0, pdf >= 0", 0.0)
    ok = (sw > 0) & (spdf > 0)
    ev_s = probe.eval(bsdf, wi[ok], swo[ok])[:, 0]
    pd_s = probe.pdf(bsdf, wi[ok], swo[ok])
    ratio = ev_s / np.where(pd_s > 0, pd_s, 1.0)
    relw = np.abs(sw[ok] - ratio) / np.maximum(np.abs(ratio), 1e-30)
    rows.exact(f"{label}: weight = eval/pdf", f"{label}: max relative |weight − eval/pdf| "
               f"at sampled directions", float(relw.max()) if relw.size else math.inf, 0.0,
               "sample() must agree with eval() and pdf()", 64 * EPS32)


def _chi2(cfg: Config, rows: Rows, label: str, spec: dict, k: int, tests: int) -> None:
    """Pearson χ² of sample() against pdf() at each of :data:`CHI2_ANGLES`; the minimum p."""
    pmin, hist_min, per_angle = 1.0, math.inf, {}
    for t in CHI2_ANGLES:
        wi = probe.direction(math.radians(t)).tolist()
        sample_func, pdf_func = mi.chi2.BSDFAdapter(spec["type"], spec, wi=wi)
        test = mi.chi2.ChiSquareTest(domain=mi.chi2.SphericalDomain(), sample_func=sample_func,
                                     pdf_func=pdf_func, sample_dim=3,
                                     sample_count=cfg.chi2_samples, res=101, ires=16,
                                     seed=cfg.seed + k)
        test.run(significance_level=stats.ALPHA, test_count=1, quiet=True)
        hist = float(np.sum(np.array(test.histogram)))
        pv = float(test.p_value) if test.p_value is not None else 0.0
        if test.fail or not math.isfinite(pv):
            pv = 0.0
        per_angle[f"{t:g}"] = {"p_value": pv, "histogram_sum": hist}
        pmin, hist_min = min(pmin, pv), min(hist_min, hist)
    rows.exact(f"{label}: χ² sampling", f"{label}: min χ² p-value of sample() vs pdf() "
               f"(θ_i 0/45/80°)", pmin, stats.sidak(stats.ALPHA, tests),
               f"Pearson χ²; Šidák level over {tests} tests", 0.0,
               relation=">=", extra_ok=hist_min > 0, histogram_min_sum=hist_min,
               per_angle=per_angle)
