r"""Check 5, ``snell``: refraction directions and Fresnel, three ways, all deterministic.

For relative indices η_rel = int_ior/ext_ior in {1.33, 1.5, 2.4} and their inverses, and
incidence from both sides (400 angles 0..89.99° plus a band around the critical angle):
:func:`phonglab.physics.optics.refract` (the seed's
T = −ηV + (η V·N − √(1 − η²(1 − (V·N)²))) N, float64), ``mi.refract`` (float32) and the
direction ``dielectric.sample`` returns with sample1 = 1 − 2⁻²⁴ (transmission whenever F < 1).
Budget: angles agree within 8·2⁻²⁴·(1/cos θ_t) rad (float32 directions; the refracted angle's
sensitivity grows as 1/cos θ_t near grazing), here taken as its maximum over non-grazing
cases 1e-5 rad; Snell residual |n₁ sin θ₁ − n₂ sin θ₂| ≤ 1e-6·n₁; Fresnel agreement within
8·2⁻²⁴(1 + 1/cos² θ_t) (F is steep near the critical angle); R + T = 1 within 1e-6.  TIR:
the seed formula reports no transmitted ray exactly where ``dielectric`` reflects with F = 1,
except within 1e-6 of the critical sin θ (float32 cannot tell them apart).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mitsuba as mi
import numpy as np

from .. import probe, registration
from ..physics import optics
from ..verdict import Row
from .common import EPS32, Config, Rows

#: Relative indices of refraction int_ior/ext_ior (their inverses are checked too).
INDICES = (1.33, 1.5, 2.4)


@dataclass
class _Worst:
    """The worst deviations over every index, side and angle."""

    angle_mi: float = 0.0         #: max angle seed vs mi.refract [rad]
    angle_bsdf: float = 0.0       #: max angle seed vs dielectric.sample [rad]
    snell: float = 0.0            #: max |n₁ sin θ₁ − n₂ sin θ₂| / n₁
    fresnel: float = 0.0          #: max |ΔF| / budget
    r_plus_t: float = 0.0         #: max |R + T − 1|
    weight: float = 0.0           #: max relative |weight − η²|
    tir_mismatch: int = 0
    tir_cases: int = 0
    min_f_tir: float = 1.0        #: min F and reflect pdf past the critical angle


def check_snell(cfg: Config) -> list[Row]:
    """Refraction and Fresnel: the seed formula, ``mi.refract`` and ``dielectric`` agree."""
    registration.register()
    worst = _Worst()
    for n_rel in INDICES + tuple(1.0 / x for x in INDICES):
        int_ior, ext_ior = (n_rel, 1.0) if n_rel >= 1 else (1.0, 1.0 / n_rel)
        bsdf = mi.load_dict({"type": "dielectric", "int_ior": int_ior, "ext_ior": ext_ior})
        for side in (+1, -1):
            # side +1: light arrives from outside (ext medium, on the normal's side).
            _measure_side(bsdf, int_ior, ext_ior, side, worst)
    return _rows(worst)


def _incident_directions(eta: float, side: int) -> np.ndarray:
    """400 angles 0..89.99° plus 101 within ±0.5° of the critical angle (if any), on ``side``."""
    deg = np.linspace(0.0, 89.99, 400)
    crit = math.degrees(math.asin(min(1.0, 1.0 / eta))) if eta > 1 else None
    angles = deg if crit is None else np.concatenate([deg, crit + np.linspace(-0.5, 0.5, 101)])
    v = probe.direction(np.radians(angles))
    v[:, 2] *= side
    return v


def _angle_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    c = np.clip(np.sum(a * b, axis=1) / (np.linalg.norm(a, axis=1)
                                         * np.linalg.norm(b, axis=1)), -1.0, 1.0)
    return np.arccos(c)


def _measure_side(bsdf, int_ior: float, ext_ior: float, side: int, worst: _Worst) -> None:
    """Compare the three refractions and the Fresnel terms for incidence from one side."""
    n1, n2 = (ext_ior, int_ior) if side > 0 else (int_ior, ext_ior)
    eta = n1 / n2
    v = _incident_directions(eta, side)
    t_seed, valid = optics.refract(v, np.array([0.0, 0.0, float(side)]), eta)
    # mi.refract(wi, cos_theta_t, eta_ti), with cos_theta_t from mi.fresnel.
    # mi.fresnel takes the signed cos θ_i (< 0 inside) and η = int_ior / ext_ior.
    F_mi, cos_t, _, eta_ti = mi.fresnel(mi.Float(v[:, 2].astype(np.float32)),
                                        mi.Float(np.float32(int_ior / ext_ior)))
    t_mi = probe.to_numpy(mi.refract(probe.to_vectors(v), cos_t, eta_ti))
    F_mi = probe.to_numpy(F_mi)
    s = probe.sample(bsdf, v, 1.0 - EPS32, (0.5, 0.5))
    wo, pdf, w = s.wo, s.pdf, s.weight[:, 0]
    bs_refl = wo[:, 2] * side > 0
    # Same float32-rounded cosine into both Fresnel implementations.
    F_seed, _ = optics.fresnel_dielectric(np.abs(v[:, 2].astype(np.float32)), eta)
    sin1 = np.sqrt(np.maximum(0.0, 1 - v[:, 2] ** 2))
    near_crit = np.abs(eta * sin1 - 1.0) < 1e-6
    ok = valid & ~near_crit
    tir = ~valid & ~near_crit
    worst.tir_cases += int(tir.sum())
    worst.tir_mismatch += int(np.sum(tir & ~bs_refl) + np.sum(ok & bs_refl))
    if tir.any():
        worst.min_f_tir = min(worst.min_f_tir, float(F_mi[tir].min()), float(pdf[tir].min()))
    cos_t_seed = np.abs(t_seed[:, 2])
    good = ok & (cos_t_seed > 1e-2)   # grazing transmission: see the module docstring
    if good.any():
        worst.angle_mi = max(worst.angle_mi, float(_angle_between(t_seed[good], t_mi[good]).max()))
        worst.angle_bsdf = max(worst.angle_bsdf,
                               float(_angle_between(t_seed[good], wo[good]).max()))
        # sin θ from the tangential components (from cos θ it loses precision near 0).
        sin_v = np.linalg.norm(v[good, :2], axis=1) / np.linalg.norm(v[good], axis=1)
        sin_t = np.linalg.norm(wo[good, :2], axis=1) / np.linalg.norm(wo[good], axis=1)
        worst.snell = max(worst.snell, float(np.abs(n1 * sin_v - n2 * sin_t).max() / n1))
        # Transmitted weight: (n1/n2)² scaling of radiance.
        worst.weight = max(worst.weight, float(np.abs(w[good] - eta * eta).max() / (eta * eta)))
    # F is steep near the critical angle: float32 rounding of 1 − η² sin² θ (≈ 2⁻²⁴)
    # moves cos θ_t by ≈ 2⁻²⁴/cos θ_t and F by ≈ 2⁻²⁴/cos² θ_t.  Budget per case:
    # b = 8·2⁻²⁴ (1 + 1/cos² θ_t); the row reports max |ΔF| / b (TIR: both exactly 1).
    cmp_f = (ok & (cos_t_seed > 1e-3)) | tir
    budget = np.where(tir, 8 * EPS32, 8 * EPS32 * (1.0 + 1.0 / np.maximum(
        cos_t_seed, 1e-3) ** 2))
    worst.fresnel = max(worst.fresnel, float((np.abs(F_seed - F_mi) / budget)[cmp_f].max()))
    # R + T: reflect with sample1 = 0 (pdf = F), transmit (pdf = 1 − F) where valid.
    pdf_r = probe.sample(bsdf, v, 0.0, (0.5, 0.5)).pdf
    both = ok & (pdf_r < 1.0)
    if both.any():
        worst.r_plus_t = max(worst.r_plus_t, float(np.abs(pdf_r[both] + pdf[both] - 1.0).max()))


def _rows(worst: _Worst) -> list[Row]:
    rows = Rows("snell")
    rows.exact("refract: seed vs mi.refract", "max angle between optics.refract (seed formula) "
               "and mi.refract [rad]", worst.angle_mi, 0.0, "same law: identical directions", 1e-5)
    rows.exact("refract: seed vs dielectric", "max angle between optics.refract and the "
               "direction dielectric.sample transmits [rad]", worst.angle_bsdf, 0.0,
               "same law: identical directions", 1e-5)
    rows.exact("Snell law", "max |n₁ sin θ₁ − n₂ sin θ₂| / n₁ of dielectric's transmitted rays",
               worst.snell, 0.0, "Snell: n₁ sin θ₁ = n₂ sin θ₂", 1e-6)
    rows.exact("TIR: seed vs dielectric", f"cases where the seed's TIR test and dielectric's "
               f"choice disagree (of {worst.tir_cases} TIR cases)", worst.tir_mismatch, 0,
               "TIR iff η² sin² θ₁ > 1", 0.0)
    rows.exact("TIR: F = 1", "min Fresnel F (mi.fresnel) and reflect pdf past the critical angle",
               worst.min_f_tir, 1.0, "total internal reflection: F = 1", 1e-6)
    rows.exact("Fresnel: seed vs mi.fresnel", "max |F(optics.fresnel_dielectric) − F(mi.fresnel)|"
               " / (8·2⁻²⁴ (1 + 1/cos² θ_t))", worst.fresnel, 1.0,
               "unpolarized Fresnel equations", 0.0, relation="<=")
    rows.exact("R + T = 1", "max |R + T − 1| of dielectric's sample pdfs (reflect, transmit)",
               worst.r_plus_t, 0.0, "energy: smooth interface absorbs nothing", 1e-6)
    rows.exact("transmitted weight = η²", "max relative |weight − (n₁/n₂)²| of transmitted samples",
               worst.weight, 0.0, "Radiance mode: L/n² conserved", 1e-6)
    return rows.finish()
