r"""Notebook 01 (radiometry): solid angle, flux, radiance along a ray, the reflection equation.

:func:`fig_solid_angle`, :func:`fig_flux`, :func:`fig_radiance_constancy`,
:func:`emitter_distance_series` + :func:`fig_emitter_distances`, :func:`fig_reflection_equation`.
The numbers come from :mod:`phonglab.physics.radiometry` (the formulas and their sources are in
its docstring), the renders from :mod:`phonglab.engine.render`; this module only plots them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from .. import probe, registration
from ..physics import radiometry
from ..engine.render import render_scene
from ..engine.scenes import load_scene
from ..engine.tonemap import to_srgb
from .common import figure, load_bsdf


def fig_solid_angle(size: float = 1.0, distances: Sequence[float] | None = None):
    """Ω = A/R² against the exact solid angle of a square and a disk of equal area, and 4π.

    Left: solid angle vs distance (log-log), the exact forms and A/R².  Right: relative error
    of A/R², which falls as (size/distance)²: A/R² is the small-patch limit.
    """
    d = np.geomspace(0.25, 20.0, 200) if distances is None else np.asarray(distances, float)
    area = size * size
    approx = radiometry.solid_angle(area, d)
    square = radiometry.solid_angle_rectangle(size, size, d)
    disk = radiometry.solid_angle_disk(size / math.sqrt(math.pi), d)
    dirs, w = radiometry.sphere_quadrature()
    fig = figure(9, 3.4)
    ax1, ax2 = fig.subplots(1, 2)
    ax1.loglog(d, approx, "k--", label="A / R²")
    ax1.loglog(d, square, label="square, exact")
    ax1.loglog(d, disk, label="disk of equal area, exact")
    ax1.axhline(2 * math.pi, color="gray", lw=0.8)
    ax1.text(d[0], 2 * math.pi * 1.15, "hemisphere 2π", fontsize=8, color="gray")
    ax1.set_xlabel("distance R (patch side = 1)")
    ax1.set_ylabel("solid angle Ω [sr]")
    ax1.set_title(f"Ω = A/R²  (whole sphere by quadrature: {w.sum() / math.pi:.6f} π)", fontsize=9)
    ax1.legend(fontsize=8)
    ax2.loglog(d, np.abs(approx - square) / square, label="square")
    ax2.loglog(d, np.abs(approx - disk) / disk, label="disk")
    ax2.set_xlabel("distance R")
    ax2.set_ylabel("|A/R² − Ω| / Ω")
    ax2.set_title("A/R² is exact in the limit of a small patch", fontsize=9)
    ax2.legend(fontsize=8)
    return fig


def fig_flux(radiance: float = 1.0, area: float = 1.0):
    """dΦ = N v cos θ dA for a tilted patch, and Φ = A ∫ L cos θ dω = π L A for a Lambertian
    emitter, by quadrature (the cos θ makes it π, not 2π)."""
    theta = np.linspace(0, math.pi / 2, 100)
    fig = figure(9, 3.2)
    ax1, ax2 = fig.subplots(1, 2)
    ax1.plot(np.degrees(theta), radiometry.particle_flux(1.0, 1.0, 1.0, theta))
    ax1.set_xlabel("tilt θ of the patch against the flow [deg]")
    ax1.set_ylabel("dΦ / (N v dA)")
    ax1.set_title("flux through a tilted patch: dΦ = N v cos θ dA", fontsize=9)
    cones = np.radians([5, 15, 30, 45, 60, 75, 90])
    total = radiometry.flux_from_radiance(radiance, area)
    inside = [radiometry.flux_from_radiance(
        lambda w, c=c: radiance * (w[:, 2] >= math.cos(c) - 1e-12), area, n_theta=512, n_phi=8)
        for c in cones]
    ax2.plot(np.degrees(theta), np.sin(theta) ** 2, "k-", label="π L A sin²θ / Φ (closed form)")
    ax2.plot(np.degrees(cones), np.array(inside) / total, "o",
             label="A ∫_cone L cos θ dω / Φ (quadrature)")
    ax2.set_xlabel("half-angle of the cone around the normal [deg]")
    ax2.set_ylabel("fraction of the flux")
    ax2.set_title(f"Lambertian emitter: Φ = {total / (math.pi * radiance * area):.6f} π L A,\n"
                  f"half of it within 45° of the normal", fontsize=8)
    ax2.legend(fontsize=7)
    return fig


def fig_radiance_constancy(radiance: float = 1.0, area_1: float = 1e-4, area_2: float = 1e-4,
                           theta_1: float = 0.3, theta_2: float = 0.6):
    """The seed's pencil of rays: dΦ ∝ 1/r², but dΦ / (dA cos θ dω) = L at both ends."""
    r = np.geomspace(0.5, 50, 60)
    p = radiometry.pencil(radiance, area_1, area_2, theta_1, theta_2, r)
    fig = figure(9, 3.2)
    ax1, ax2 = fig.subplots(1, 2)
    ax1.loglog(r, p.flux, label="dΦ = L dA₁ cos θ₁ dω₁")
    ax1.loglog(r, p.etendue_1, "--", label="dA₁ cos θ₁ dω₁")
    ax1.loglog(r, p.etendue_2, ":", lw=3, label="dA₂ cos θ₂ dω₂")
    ax1.set_xlabel("distance r between the patches")
    ax1.set_title("flux and étendue fall as 1/r², and the étendues agree", fontsize=9)
    ax1.legend(fontsize=8)
    ax2.semilogx(r, p.radiance_1, label="L₁ = dΦ / (dA₁ cos θ₁ dω₁)")
    ax2.semilogx(r, p.radiance_2, "--", label="L₂ = dΦ / (dA₂ cos θ₂ dω₂)")
    ax2.set_ylim(0, 1.5 * radiance)
    ax2.set_xlabel("distance r")
    ax2.set_ylabel("radiance")
    ax2.set_title("radiance is constant along the ray", fontsize=9)
    ax2.legend(fontsize=8)
    return fig


@dataclass
class EmitterSeries:
    """Renders of nb_emitter_distance.xml at several distances."""

    distances: np.ndarray
    images: list[np.ndarray]
    centre_radiance: np.ndarray        #: value of the central pixel (radiance seen)
    solid_angle_measured: np.ndarray   #: Σ pixel value / L · pixel solid angle
    solid_angle_exact: np.ndarray      #: 4 arcsin(s² / (s² + 4d²))
    radiance: float
    size: float


def emitter_distance_series(distances: Sequence[float] = (2.0, 4.0, 8.0), spp: int = 4,
                            res: int = 64, radiance: float = 1.0, size: float = 1.0,
                            fov: float = 30.0) -> EmitterSeries:
    """Render the square emitter of ``nb_emitter_distance.xml`` from each distance.

    The measured solid angle sums, over pixels, (pixel value / L) × the pixel's solid angle
    (:func:`phonglab.physics.radiometry.pixel_solid_angles`; the scene's fov is 30°).
    """
    registration.register()
    pix = radiometry.pixel_solid_angles(res, res, fov)
    images, centre, omega = [], [], []
    for d in distances:
        scene = load_scene("nb_emitter_distance", distance=str(d), spp=str(spp), res=str(res),
                           radiance=str(radiance), size=str(size))
        img = render_scene(scene, spp, seed=0).image[..., 0]
        images.append(img)
        centre.append(float(img[res // 2, res // 2]))
        omega.append(float(np.sum(img / radiance * pix)))
    d = np.asarray(distances, dtype=np.float64)
    return EmitterSeries(d, images, np.array(centre), np.array(omega),
                         radiometry.solid_angle_rectangle(size, size, d), radiance, size)


def fig_emitter_distances(series: EmitterSeries):
    """The renders side by side, titled with the radiance seen and the solid angle covered."""
    n = len(series.images)
    fig = figure(2.6 * n, 3.0)
    axes = np.atleast_1d(fig.subplots(1, n))
    for ax, d, img, L, om, ex in zip(axes, series.distances, series.images,
                                     series.centre_radiance, series.solid_angle_measured,
                                     series.solid_angle_exact):
        ax.imshow(to_srgb(img), cmap="gray", vmin=0, vmax=1, interpolation="nearest")
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_title(f"d = {d:g}: centre pixel L = {L:.4f}\n"
                     f"Ω = {om:.4f} sr (exact {ex:.4f})", fontsize=8)
    return fig


def fig_reflection_equation(exponents: Sequence[float] = (1, 10, 100), kd: float = 0.5,
                            ks: float = 0.3, n_angles: int = 19, mc_samples: int = 20000):
    """L_r(θ_r) = ∫ f_r L_i cos θ_i dω_i by quadrature of each plugin's eval, two skies.

    Left, a uniform sky L_i = 1 (the directional albedo; Monte Carlo means of the plugin's
    ``sample`` weights as dots).  Right, a sky brighter at the zenith, L_i = cos θ_i.
    """
    thetas = np.linspace(0.0, math.radians(85), n_angles)
    bsdfs = {"lambert ρ = %.1f" % (kd + ks): load_bsdf("lambert", reflectance=kd + ks)}
    for p in exponents:
        bsdfs[f"phong p = {p:g}"] = load_bsdf("phong", diffuse_reflectance=kd,
                                              specular_reflectance=ks, exponent=float(p))
    fig = figure(9, 3.4)
    ax1, ax2 = fig.subplots(1, 2, sharey=True)
    views = probe.direction(thetas)
    for k, (name, bsdf) in enumerate(bsdfs.items()):
        color = f"C{k}"
        uniform = radiometry.reflected_radiance(bsdf, views)[:, 0]
        zenith = radiometry.reflected_radiance(bsdf, views, lambda w: w[:, 2])[:, 0]
        ax1.plot(np.degrees(thetas), uniform, color=color, label=name)
        mc_t = thetas[::6]
        mc = [radiometry.directional_albedo(bsdf, probe.direction(t), mc_samples, seed=k)
              for t in mc_t]
        ax1.errorbar(np.degrees(mc_t), [m.mean[0] for m in mc],
                     yerr=[3 * m.stderr[0] for m in mc], fmt="o", color=color, ms=3)
        ax2.plot(np.degrees(thetas), zenith, color=color, label=name)
    ax1.axhline(kd + ks, color="gray", ls=":", lw=0.8)
    ax1.set_title("uniform sky L_i = 1 (dots: mean sample weight ± 3 s.e.)", fontsize=9)
    ax2.set_title("zenith-bright sky L_i = cos θ_i", fontsize=9)
    for ax in (ax1, ax2):
        ax.set_xlabel("view angle θ_r [deg]")
    ax1.set_ylabel("reflected radiance L_r")
    ax1.legend(fontsize=7)
    return fig
