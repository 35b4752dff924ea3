r"""Notebook 03 (refraction): Snell's law, Fresnel reflectance, ours against Mitsuba's.

:func:`fig_snell`, :func:`fig_fresnel`, :func:`refraction_agreement` +
:func:`fig_refraction_agreement`.  The formulas are :mod:`phonglab.physics.optics`'s; Mitsuba's
``mi.refract`` and its ``dielectric`` BSDF (through :mod:`phonglab.probe`) are what they are
compared with.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mitsuba as mi
import numpy as np

from .. import probe, registration
from ..physics import optics
from .common import figure


def fig_snell(n_inside: float = 1.5, n_outside: float = 1.0):
    """θ_t against θ_i from phonglab.physics.optics.refract, entering and leaving the denser medium,
    with the critical angle, and the Snell residual |n₁ sin θ₁ − n₂ sin θ₂|."""
    theta = np.linspace(0.0, math.pi / 2 * 0.999, 400)
    v = np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=-1)
    nrm = np.array([0.0, 0.0, 1.0])
    fig = figure(9, 3.4)
    ax1, ax2 = fig.subplots(1, 2)
    for n1, n2, style in ((n_outside, n_inside, "-"), (n_inside, n_outside, "--")):
        t, valid = optics.refract(v, nrm, n1 / n2)
        theta_t = np.degrees(np.arccos(np.clip(-t[:, 2], -1, 1)))
        ax1.plot(np.degrees(theta[valid]), theta_t[valid], style,
                 label=f"n₁ = {n1:g} → n₂ = {n2:g}")
        res = optics.snell_residual(v[valid], t[valid], nrm, n1, n2)
        ax2.semilogy(np.degrees(theta[valid]), np.maximum(res, 1e-18), style,
                     label=f"{n1:g} → {n2:g}, max {res.max():.1e}")
    crit = float(np.degrees(optics.critical_angle(n_inside / n_outside)))
    ax1.axvline(crit, color="r", ls=":", label=f"critical angle {crit:.2f}°")
    ax1.plot([0, 90], [0, 90], color="gray", lw=0.6)
    ax1.set_xlabel("θ₁ [deg]")
    ax1.set_ylabel("θ₂ [deg]")
    ax1.set_title("Snell: n₁ sin θ₁ = n₂ sin θ₂ (no ray past the critical angle)", fontsize=9)
    ax1.legend(fontsize=7)
    ax2.set_xlabel("θ₁ [deg]")
    ax2.set_title("|n₁ sin θ₁ − n₂ sin θ₂| of optics.refract (float64)", fontsize=9)
    ax2.legend(fontsize=7)
    return fig


def fig_fresnel(n_inside: float = 1.5, n_outside: float = 1.0):
    """Unpolarized Fresnel reflectance both ways; F = 1 (total internal reflection) past the
    critical angle when leaving the denser medium."""
    theta = np.linspace(0.0, math.pi / 2, 400)
    fig = figure(5.5, 3.4)
    ax = fig.subplots()
    for n1, n2, style in ((n_outside, n_inside, "-"), (n_inside, n_outside, "--")):
        F, _ = optics.fresnel_dielectric(np.cos(theta), n1 / n2)
        ax.plot(np.degrees(theta), F, style, label=f"{n1:g} → {n2:g}")
    crit = float(np.degrees(optics.critical_angle(n_inside / n_outside)))
    ax.axvline(crit, color="r", ls=":", label=f"critical angle {crit:.2f}°")
    ax.set_xlabel("incidence angle θ₁ [deg]")
    ax.set_ylabel("reflectance F")
    ax.set_title("Fresnel reflectance and total internal reflection", fontsize=9)
    ax.legend(fontsize=8)
    return fig


@dataclass
class RefractionAgreement:
    """phonglab.physics.optics.refract against mi.refract and the built-in dielectric's sample."""

    thetas: np.ndarray              #: incidence angles [rad] (from the outside, and inside)
    inside: np.ndarray              #: bool, incidence from inside the denser medium
    angle_vs_mi_refract: np.ndarray   #: angle between ours and mi.refract's direction [rad]
    angle_vs_dielectric: np.ndarray   #: angle between ours and dielectric's sampled wo [rad]
    fresnel_ours: np.ndarray
    fresnel_dielectric: np.ndarray  #: 1 − pdf of the dielectric's transmission sample
    tir_ours: np.ndarray            #: bool, our refract says no transmitted ray
    tir_dielectric: np.ndarray      #: bool, dielectric reflected even with sample1 ≈ 1
    int_ior: float = 1.5
    ext_ior: float = 1.0


def refraction_agreement(int_ior: float = 1.5, ext_ior: float = 1.0,
                         n_angles: int = 91) -> RefractionAgreement:
    """Refract the same directions three ways and measure the angles between the results.

    Directions are in the dielectric's local frame (normal +z points outside).  Ours:
    ``optics.refract(wi, n, eta)`` with n on wi's side and eta = n(wi side) / n(other side).
    Mitsuba: ``mi.fresnel`` then ``mi.refract(wi, cos_theta_t, eta_ti)``.  Dielectric:
    ``bsdf.sample`` with sample1 = 0.99999 (transmission whenever F < 0.99999).
    """
    registration.register()
    th = np.linspace(0.0, math.radians(89.0), n_angles)
    thetas = np.concatenate([th, th])
    inside = np.concatenate([np.zeros(n_angles, bool), np.ones(n_angles, bool)])
    z = np.where(inside, -np.cos(thetas), np.cos(thetas))
    wi = np.stack([np.sin(thetas), np.zeros_like(thetas), z], axis=-1)
    n_side = np.where(inside[:, None], [0.0, 0.0, -1.0], [0.0, 0.0, 1.0])
    eta_ours = np.where(inside, int_ior / ext_ior, ext_ior / int_ior)
    ours, valid = optics.refract(wi, n_side, eta_ours)
    F_ours, _ = optics.fresnel_dielectric(np.abs(z), eta_ours)

    wi_mi = probe.to_vectors(wi)
    cos_i = mi.Frame3f.cos_theta(wi_mi)
    _, cos_t, _, eta_ti = mi.fresnel(cos_i, mi.Float(int_ior / ext_ior))
    t_mi = probe.to_numpy(mi.refract(wi_mi, cos_t, eta_ti))

    # The dielectric transmits whenever F < sample1 = 0.99999 (sample2 is unused by a delta lobe).
    bsdf = mi.load_dict({"type": "dielectric", "int_ior": int_ior, "ext_ior": ext_ior})
    s = probe.sample(bsdf, wi, np.full(len(wi), 0.99999), [0.5, 0.5])
    transmitted = (s.sampled_type & int(mi.BSDFFlags.DeltaTransmission)) != 0
    F_diel = np.where(transmitted, 1.0 - s.pdf, 1.0)

    ang_mi = np.where(valid, optics.angle_between(ours, t_mi), np.nan)
    ang_diel = np.where(valid & transmitted, optics.angle_between(ours, s.wo), np.nan)
    return RefractionAgreement(thetas, inside, ang_mi, ang_diel, F_ours, F_diel, ~valid,
                               ~transmitted, int_ior, ext_ior)


def fig_refraction_agreement(r: RefractionAgreement):
    """Angles between our refracted direction and Mitsuba's two, and the Fresnel terms."""
    fig = figure(9, 3.4)
    ax1, ax2 = fig.subplots(1, 2)
    for inside, style, label in ((False, "-", "from outside"), (True, "--", "from inside")):
        m = r.inside == inside
        deg = np.degrees(r.thetas[m])
        ax1.semilogy(deg, np.maximum(r.angle_vs_mi_refract[m], 1e-12), style, color="C0",
                     lw=4, alpha=0.4, label=f"vs mi.refract, {label}")
        ax1.semilogy(deg, np.maximum(r.angle_vs_dielectric[m], 1e-12), style, color="C1",
                     label=f"vs dielectric sample, {label}")
        ax2.plot(deg, r.fresnel_ours[m], style, color="k", lw=2, alpha=0.4,
                 label=f"optics.fresnel_dielectric, {label}")
        ax2.plot(deg, r.fresnel_dielectric[m], style, color="C1", lw=1,
                 label=f"dielectric (1 − pdf of T), {label}")
    ax1.axhline(float(np.finfo(np.float32).eps), color="gray", ls=":", lw=0.8)
    ax1.text(0, float(np.finfo(np.float32).eps) * 1.3, "float32 ε", fontsize=7, color="gray")
    ax1.set_xlabel("incidence angle [deg]")
    ax1.set_ylabel("angle between directions [rad] (floored at 1e-12)")
    ax1.set_title(f"our refraction vs Mitsuba (int_ior {r.int_ior:g}, ext_ior {r.ext_ior:g})",
                  fontsize=9)
    ax1.legend(fontsize=6)
    ax2.set_xlabel("incidence angle [deg]")
    ax2.set_ylabel("F")
    ax2.set_title("Fresnel reflectance: ours and dielectric's", fontsize=9)
    ax2.legend(fontsize=6)
    return fig
