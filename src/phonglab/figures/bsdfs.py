r"""Notebook 02 (Lambert and Phong): the Phong lobe, rows of spheres, the furnace test.

:func:`fig_phong_lobes` (from :func:`phong_lobe_curves`), :func:`render_sphere_row` +
:func:`fig_sphere_rows`, :func:`albedo_curves` + :func:`fig_albedo`, :func:`render_furnace` +
:func:`fig_furnace` (with :func:`furnace_profile`).  The plugins are probed through
:mod:`phonglab.probe`, the albedo computed by :mod:`phonglab.physics.radiometry` (quadrature of
``eval`` and the mean ``sample`` weight); this module arranges and plots the numbers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

import mitsuba as mi
import numpy as np

from .. import probe, registration
from ..physics import radiometry
from ..engine.render import render_scene
from ..engine.scenes import load_scene
from ..engine.tonemap import to_srgb
from .common import figure, load_bsdf

#: The seed's exponents (D. Zorin, "Lighting": p = 0, 1, 2, 10, 25, 100).
SEED_EXPONENTS = (0, 1, 2, 10, 25, 100)
#: The seed's plastic and metal (k_d + k_s <= 1 in every channel; "k_spec = k_diff" for metal
#: is read as a coloured specular with almost no diffuse, which keeps the sum below 1).
PLASTIC = {"kd": "0.6, 0.08, 0.06", "ks": "0.3, 0.3, 0.3"}
METAL = {"kd": "0.06, 0.01, 0.01", "ks": "0.8, 0.2, 0.12"}


def phong_lobe_curves(exponents: Sequence[float] = SEED_EXPONENTS, theta_i_deg: float = 45.0,
                      n: int = 721) -> tuple[np.ndarray, dict[float, np.ndarray]]:
    """The specular lobe (k_d = 0, k_s = 1) in the plane of incidence, from phong's ``eval``.

    Returns (θ_o in radians from −π/2 to π/2, positive on the mirror side; {p: f_r cos θ_o}).
    One plugin instance is swept through the exponents with ``mi.traverse`` (opaque
    parameter: no recompilation).
    """
    bsdf = load_bsdf("phong", diffuse_reflectance=0.0, specular_reflectance=1.0, exponent=1.0)
    params = mi.traverse(bsdf)
    t = np.linspace(-math.pi / 2, math.pi / 2, n)
    wo = probe.direction(t)
    wi = probe.direction(math.radians(theta_i_deg), math.pi)   # light from the −x side
    out = {}
    for p in exponents:
        params["exponent"] = float(p)
        params.update()
        out[float(p)] = probe.eval(bsdf, wi, wo)[:, 0]
    return t, out


def fig_phong_lobes(exponents: Sequence[float] = SEED_EXPONENTS, theta_i_deg: float = 45.0):
    """Polar plots of the specular lobe f_r cos θ_o (phong's eval) for each exponent.

    Each panel is scaled to its own peak (printed), as in the seed's slides; the arrows are
    the incident direction and its mirror direction R.
    """
    t, curves = phong_lobe_curves(exponents, theta_i_deg)
    n = len(curves)
    fig = figure(2.3 * n, 2.6)
    ti = math.radians(theta_i_deg)
    for k, (p, v) in enumerate(curves.items()):
        ax = fig.add_subplot(1, n, k + 1, projection="polar")
        ax.set_theta_zero_location("N")
        ax.set_theta_direction(-1)
        ax.set_thetamin(-90)
        ax.set_thetamax(90)
        peak = float(v.max())
        ax.fill(t, v / peak, alpha=0.35, color="C1")
        ax.plot(t, v / peak, color="C1")
        ax.annotate("", xy=(0, 0), xytext=(-ti, 1.0),
                    arrowprops=dict(arrowstyle="->", color="C0"))
        ax.plot([ti, ti], [0, 1.0], color="k", ls=":", lw=0.8)
        ax.set_rticks([])
        ax.set_xticks(np.radians([-90, -45, 0, 45, 90]))
        ax.tick_params(labelsize=6)
        ax.set_title(f"p = {p:g}\npeak f_r cos θ = {peak:.3g}", fontsize=8)
    return fig


def render_sphere_row(spp: int = 16, exponents: Sequence[float] = SEED_EXPONENTS, seed: int = 0,
                      **defaults) -> np.ndarray:
    """Render ``nb_sphere_row.xml`` (one sphere per exponent); ``defaults`` override its
    ``<default>`` entries (kd, ks as "r, g, b" strings, width, height, irradiance)."""
    registration.register()
    if len(exponents) != 6:
        raise ValueError(f"nb_sphere_row.xml holds 6 spheres; give 6 exponents, got {len(exponents)}")
    params = {f"p{k}": str(float(p)) for k, p in enumerate(exponents)}
    params.update({k: str(v) for k, v in defaults.items()})
    scene = load_scene("nb_sphere_row", spp=str(spp), **params)
    return render_scene(scene, spp, seed=seed).image


def fig_sphere_rows(rows: dict[str, np.ndarray], exponents: Sequence[float] = SEED_EXPONENTS):
    """Rows of spheres (label → image) stacked, each sphere labelled with its exponent."""
    n = len(rows)
    first = next(iter(rows.values()))
    h, w = first.shape[:2]
    fig = figure(9, 9 * h / w * n + 0.4 * n)
    axes = np.atleast_1d(fig.subplots(n, 1))
    for ax, (label, img) in zip(axes, rows.items()):
        ax.imshow(to_srgb(img), interpolation="nearest")
        ax.set_yticks([])
        ax.set_xticks((np.arange(len(exponents)) + 0.5) * w / len(exponents))
        ax.set_xticklabels([f"p = {p:g}" for p in exponents], fontsize=8)
        ax.set_title(label, fontsize=9)
    return fig


@dataclass
class AlbedoCurves:
    """Directional albedo a(θ) of phong by quadrature of eval and by the mean sample weight."""

    thetas: np.ndarray                                   #: incidence angles [rad]
    quadrature: dict[float, np.ndarray] = field(default_factory=dict)   #: p → a(θ)
    mc_mean: dict[float, np.ndarray] = field(default_factory=dict)      #: p → mean weight
    mc_stderr: dict[float, np.ndarray] = field(default_factory=dict)    #: p → its s.e.
    kd: float = 0.5
    ks: float = 0.3
    samples: int = 0


def albedo_curves(exponents: Sequence[float] = SEED_EXPONENTS, kd: float = 0.5, ks: float = 0.3,
                  n_angles: int = 10, samples: int = 20000, seed: int = 0) -> AlbedoCurves:
    """The furnace test for phong: a(θ) = ∫ f_r cos θ_o dω_o, two ways, for each exponent.

    Expected: a = k_d + k_s at θ = 0 for every p (each lobe integrates to its reflectance),
    a < k_d + k_s at oblique incidence (glossy lobe partly below the horizon), never > 1.
    """
    thetas = np.linspace(0.0, math.radians(85.0), n_angles)
    bsdf = load_bsdf("phong", diffuse_reflectance=kd, specular_reflectance=ks, exponent=1.0)
    params = mi.traverse(bsdf)
    out = AlbedoCurves(thetas, kd=kd, ks=ks, samples=samples)
    for p in exponents:
        params["exponent"] = float(p)
        params.update()
        q = radiometry.reflected_radiance(bsdf, probe.direction(thetas))[:, 0]
        m, s = [], []
        for k, t in enumerate(thetas):
            wi = probe.direction(t)
            est = radiometry.directional_albedo(bsdf, wi, samples, seed=seed + k)
            m.append(est.mean[0])
            s.append(est.stderr[0])
        out.quadrature[float(p)] = np.array(q)
        out.mc_mean[float(p)] = np.array(m)
        out.mc_stderr[float(p)] = np.array(s)
    return out


def fig_albedo(curves: AlbedoCurves):
    """a(θ) per exponent: lines by quadrature of eval, dots ± 3 s.e. from sample."""
    fig = figure(6.5, 3.6)
    ax = fig.subplots()
    deg = np.degrees(curves.thetas)
    for k, p in enumerate(curves.quadrature):
        ax.plot(deg, curves.quadrature[p], color=f"C{k}", label=f"p = {p:g}")
        ax.errorbar(deg, curves.mc_mean[p], yerr=3 * curves.mc_stderr[p], fmt="o", ms=3,
                    color=f"C{k}")
    ax.axhline(curves.kd + curves.ks, color="k", ls="--", lw=0.8, label="k_d + k_s")
    ax.axhline(1.0, color="r", ls=":", lw=0.8, label="1 (energy bound)")
    ax.set_xlabel("incidence angle θ [deg]")
    ax.set_ylabel("directional albedo a(θ)")
    ax.set_ylim(0, 1.05)
    ax.set_title(f"furnace test: lines = quadrature of eval, dots = mean sample weight "
                 f"± 3 s.e. ({curves.samples} samples)", fontsize=8)
    ax.legend(fontsize=7, ncol=2)
    return fig


def render_furnace(spp: int = 64, passes: int = 4, seed: int = 0, **defaults):
    """Render ``nb_furnace_sphere.xml`` (phong sphere under a unit sky, BSDF sampling only);
    returns phonglab.engine.render.RenderResult (image and per-pixel standard error)."""
    registration.register()
    scene = load_scene("nb_furnace_sphere", spp=str(spp), **{k: str(v) for k, v in defaults.items()})
    return render_scene(scene, spp, seed=seed, passes=passes)


def furnace_profile(result, kd: float = 0.5, ks: float = 0.3, exponent: float = 10.0,
                    extent: float = 1.1):
    """The middle row of a furnace render against a(θ) by quadrature.

    The camera is orthographic over [−extent, extent]; at x on the unit sphere's middle row
    the view makes θ = asin|x| with the normal.  Returns (x, pixel values, their s.e.,
    quadrature a(θ)) for pixels on the sphere.
    """
    img = result.image[..., 0]
    se = result.stderr[..., 0] if result.stderr is not None else np.zeros_like(img)
    h, w = img.shape
    x = ((np.arange(w) + 0.5) / w * 2.0 - 1.0) * extent
    inside = np.abs(x) < 0.97
    bsdf = load_bsdf("phong", diffuse_reflectance=kd, specular_reflectance=ks,
                     exponent=float(exponent))
    a = radiometry.reflected_radiance(bsdf, probe.direction(np.arcsin(np.abs(x[inside]))))[:, 0]
    return x[inside], img[h // 2, inside], se[h // 2, inside], a


def fig_furnace(result, kd: float = 0.5, ks: float = 0.3, exponent: float = 10.0):
    """The furnace render and its middle row against the quadrature albedo."""
    x, row, se, a = furnace_profile(result, kd, ks, exponent)
    fig = figure(8.5, 3.2)
    ax1, ax2 = fig.subplots(1, 2, width_ratios=[1, 1.7])
    ax1.imshow(to_srgb(result.image), interpolation="nearest")
    ax1.set_xticks([])
    ax1.set_yticks([])
    ax1.set_title("phong sphere in a white furnace", fontsize=9)
    ax2.plot(x, a, "k-", label="a(θ), quadrature of eval")
    ax2.errorbar(x, row, yerr=3 * se, fmt=".", ms=3, label="middle row ± 3 s.e.")
    ax2.axhline(kd + ks, color="gray", ls="--", lw=0.8, label="k_d + k_s")
    ax2.set_xlabel("x on the sphere (θ = asin |x|)")
    ax2.set_ylabel("radiance = albedo")
    ax2.set_ylim(0, 1.05)
    ax2.legend(fontsize=7)
    return fig
