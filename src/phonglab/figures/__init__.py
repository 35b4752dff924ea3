r"""The computations and charts behind the notebooks (one call per notebook cell).

Every chart function returns a :class:`matplotlib.figure.Figure` built without pyplot (no
global state: safe in scripts, tests and notebooks; ``fig.savefig(path)`` writes it).  Data
functions return plain numpy arrays or small dataclasses so that a notebook can print the
numbers it plots.  The physics lives in :mod:`phonglab.radiometry`, :mod:`phonglab.optics` and
the plugins; this module only arranges it.

Notebook 01 (radiometry): :func:`fig_solid_angle`, :func:`fig_flux`,
:func:`fig_radiance_constancy`, :func:`emitter_distance_series` + :func:`fig_emitter_distances`,
:func:`fig_reflection_equation`.
Notebook 02 (Lambert and Phong): :func:`fig_phong_lobes`, :func:`render_sphere_row` +
:func:`fig_sphere_rows`, :func:`albedo_curves` + :func:`fig_albedo`, :func:`render_furnace` +
:func:`fig_furnace`.
Notebook 03 (refraction): :func:`fig_snell`, :func:`fig_fresnel`,
:func:`refraction_agreement` + :func:`fig_refraction_agreement`.
Notebook 04 (speed against accuracy): :func:`convergence_curves` + :func:`fig_convergence`,
:func:`efficiency_table`; the stability map and the render charts come from
:mod:`phonglab.bench`, the plan from :mod:`phonglab.planner`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

import numpy as np

from ..physics import optics, radiometry
from ..tonemap import to_srgb

#: The seed's exponents (D. Zorin, "Lighting": p = 0, 1, 2, 10, 25, 100).
SEED_EXPONENTS = (0, 1, 2, 10, 25, 100)
#: The seed's plastic and metal (k_d + k_s <= 1 in every channel; "k_spec = k_diff" for metal
#: is read as a coloured specular with almost no diffuse, which keeps the sum below 1).
PLASTIC = {"kd": "0.6, 0.08, 0.06", "ks": "0.3, 0.3, 0.3"}
METAL = {"kd": "0.06, 0.01, 0.01", "ks": "0.8, 0.2, 0.12"}


def _figure(width: float, height: float, **kw):
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), layout="constrained", **kw)


def save(fig, path: str | Path, dpi: int = 80) -> Path:
    """Write a figure as PNG (folders created)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    return path


def _register(variant: str | None = None) -> str:
    from .. import registration

    return registration.register(variant)


def load_bsdf(kind: str, **params):
    """A BSDF plugin instance, ``load_bsdf("phong", exponent=10)`` (registers phonglab first)."""
    _register()
    import mitsuba as mi

    return mi.load_dict({"type": kind, **params})


# =============================================================================== 01 radiometry
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
    fig = _figure(9, 3.4)
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
    fig = _figure(9, 3.2)
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
    fig = _figure(9, 3.2)
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
    (:func:`phonglab.radiometry.pixel_solid_angles`; the scene's fov is 30°).
    """
    from ..scenes import load_scene
    from ..render import render_scene

    _register()
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
    fig = _figure(2.6 * n, 3.0)
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
    fig = _figure(9, 3.4)
    ax1, ax2 = fig.subplots(1, 2, sharey=True)
    for k, (name, bsdf) in enumerate(bsdfs.items()):
        color = f"C{k}"
        views = np.array([radiometry.direction(t) for t in thetas])
        uniform = radiometry.reflected_radiance(bsdf, views)[:, 0]
        zenith = radiometry.reflected_radiance(bsdf, views, lambda w: w[:, 2])[:, 0]
        ax1.plot(np.degrees(thetas), uniform, color=color, label=name)
        mc_t = thetas[::6]
        mc = [radiometry.directional_albedo(bsdf, radiometry.direction(t), mc_samples, seed=k)
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


# =============================================================================== 02 Lambert/Phong
def phong_lobe_curves(exponents: Sequence[float] = SEED_EXPONENTS, theta_i_deg: float = 45.0,
                      n: int = 721) -> tuple[np.ndarray, dict[float, np.ndarray]]:
    """The specular lobe (k_d = 0, k_s = 1) in the plane of incidence, from phong's ``eval``.

    Returns (θ_o in radians from −π/2 to π/2, positive on the mirror side; {p: f_r cos θ_o}).
    One plugin instance is swept through the exponents with ``mi.traverse`` (opaque
    parameter: no recompilation).
    """
    import mitsuba as mi

    bsdf = load_bsdf("phong", diffuse_reflectance=0.0, specular_reflectance=1.0, exponent=1.0)
    params = mi.traverse(bsdf)
    t = np.linspace(-math.pi / 2, math.pi / 2, n)
    wo = np.stack([np.sin(t), np.zeros_like(t), np.cos(t)], axis=-1)
    wi = radiometry.direction(math.radians(theta_i_deg), math.pi)   # light from the −x side
    out = {}
    for p in exponents:
        params["exponent"] = float(p)
        params.update()
        out[float(p)] = radiometry.bsdf_eval(bsdf, wi, wo)[:, 0]
    return t, out


def fig_phong_lobes(exponents: Sequence[float] = SEED_EXPONENTS, theta_i_deg: float = 45.0):
    """Polar plots of the specular lobe f_r cos θ_o (phong's eval) for each exponent.

    Each panel is scaled to its own peak (printed), as in the seed's slides; the arrows are
    the incident direction and its mirror direction R.
    """
    t, curves = phong_lobe_curves(exponents, theta_i_deg)
    n = len(curves)
    fig = _figure(2.3 * n, 2.6)
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
    from ..scenes import load_scene
    from ..render import render_scene

    _register()
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
    fig = _figure(9, 9 * h / w * n + 0.4 * n)
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
    import mitsuba as mi

    thetas = np.linspace(0.0, math.radians(85.0), n_angles)
    bsdf = load_bsdf("phong", diffuse_reflectance=kd, specular_reflectance=ks, exponent=1.0)
    params = mi.traverse(bsdf)
    out = AlbedoCurves(thetas, kd=kd, ks=ks, samples=samples)
    for p in exponents:
        params["exponent"] = float(p)
        params.update()
        q = radiometry.reflected_radiance(bsdf, np.array([radiometry.direction(t)
                                                          for t in thetas]))[:, 0]
        m, s = [], []
        for k, t in enumerate(thetas):
            wi = radiometry.direction(t)
            est = radiometry.directional_albedo(bsdf, wi, samples, seed=seed + k)
            m.append(est.mean[0])
            s.append(est.stderr[0])
        out.quadrature[float(p)] = np.array(q)
        out.mc_mean[float(p)] = np.array(m)
        out.mc_stderr[float(p)] = np.array(s)
    return out


def fig_albedo(curves: AlbedoCurves):
    """a(θ) per exponent: lines by quadrature of eval, dots ± 3 s.e. from sample."""
    fig = _figure(6.5, 3.6)
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
    returns phonglab.render.RenderResult (image and per-pixel standard error)."""
    from ..scenes import load_scene
    from ..render import render_scene

    _register()
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
    a = radiometry.reflected_radiance(
        bsdf, np.array([radiometry.direction(math.asin(abs(v))) for v in x[inside]]))[:, 0]
    return x[inside], img[h // 2, inside], se[h // 2, inside], a


def fig_furnace(result, kd: float = 0.5, ks: float = 0.3, exponent: float = 10.0):
    """The furnace render and its middle row against the quadrature albedo."""
    x, row, se, a = furnace_profile(result, kd, ks, exponent)
    fig = _figure(8.5, 3.2)
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


# =============================================================================== 03 refraction
def fig_snell(n_inside: float = 1.5, n_outside: float = 1.0):
    """θ_t against θ_i from phonglab.optics.refract, entering and leaving the denser medium,
    with the critical angle, and the Snell residual |n₁ sin θ₁ − n₂ sin θ₂|."""
    theta = np.linspace(0.0, math.pi / 2 * 0.999, 400)
    v = np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=-1)
    nrm = np.array([0.0, 0.0, 1.0])
    fig = _figure(9, 3.4)
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
    fig = _figure(5.5, 3.4)
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
    """phonglab.optics.refract against mi.refract and the built-in dielectric's sample."""

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
    import mitsuba as mi

    _register()
    th = np.linspace(0.0, math.radians(89.0), n_angles)
    thetas = np.concatenate([th, th])
    inside = np.concatenate([np.zeros(n_angles, bool), np.ones(n_angles, bool)])
    z = np.where(inside, -np.cos(thetas), np.cos(thetas))
    wi = np.stack([np.sin(thetas), np.zeros_like(thetas), z], axis=-1)
    n_side = np.where(inside[:, None], [0.0, 0.0, -1.0], [0.0, 0.0, 1.0])
    eta_ours = np.where(inside, int_ior / ext_ior, ext_ior / int_ior)
    ours, valid = optics.refract(wi, n_side, eta_ours)
    F_ours, _ = optics.fresnel_dielectric(np.abs(z), eta_ours)

    wi_mi = mi.Vector3f(*(mi.Float(wi[:, k].astype(np.float32)) for k in range(3)))
    cos_i = mi.Frame3f.cos_theta(wi_mi)
    _, cos_t, _, eta_ti = mi.fresnel(cos_i, mi.Float(int_ior / ext_ior))
    t_mi = radiometry._to_numpy(mi.refract(wi_mi, cos_t, eta_ti))

    bsdf = mi.load_dict({"type": "dielectric", "int_ior": int_ior, "ext_ior": ext_ior})
    wo, pdf, stype = _dielectric_sample(bsdf, wi)
    transmitted = (stype & int(mi.BSDFFlags.DeltaTransmission)) != 0
    F_diel = np.where(transmitted, 1.0 - pdf, 1.0)

    def angle(a, b):
        a = a / np.maximum(np.linalg.norm(a, axis=-1, keepdims=True), 1e-30)
        b = b / np.maximum(np.linalg.norm(b, axis=-1, keepdims=True), 1e-30)
        # atan2(|a × b|, a·b) keeps precision for tiny angles (arccos does not).
        return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.sum(a * b, axis=-1))

    ang_mi = np.where(valid, angle(ours, t_mi), np.nan)
    ang_diel = np.where(valid & transmitted, angle(ours, wo), np.nan)
    return RefractionAgreement(thetas, inside, ang_mi, ang_diel, F_ours, F_diel, ~valid,
                               ~transmitted, int_ior, ext_ior)


def _dielectric_sample(bsdf, wi: np.ndarray):
    """The dielectric's sample for each wi with sample1 = 0.99999 (transmission unless F ≈ 1)."""
    dr, mi = radiometry._require_jit()
    n = len(wi)
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.n = mi.Normal3f(0.0, 0.0, 1.0)
    si.sh_frame = mi.Frame3f(si.n)
    si.wi = mi.Vector3f(*(mi.Float(wi[:, k].astype(np.float32)) for k in range(3)))
    bs, _ = bsdf.sample(mi.BSDFContext(), si, mi.Float(np.full(n, 0.99999, np.float32)),
                        mi.Point2f(0.5, 0.5))
    return (radiometry._to_numpy(bs.wo), np.array(bs.pdf, dtype=np.float64),
            np.array(bs.sampled_type, dtype=np.int64))


def fig_refraction_agreement(r: RefractionAgreement):
    """Angles between our refracted direction and Mitsuba's two, and the Fresnel terms."""
    fig = _figure(9, 3.4)
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


# =============================================================================== docs
@dataclass
class ConvergenceCurves:
    """RMSE of each estimator against N (S seeds), with its prediction σ/√N."""

    problem_label: str
    exact: float
    n: np.ndarray                                    #: sample counts
    rmse: dict[str, np.ndarray] = field(default_factory=dict)       #: relative RMSE per method
    predicted: dict[str, np.ndarray] = field(default_factory=dict)  #: σ/(μ√N) per method
    #: time of one N-sample estimate: N × the per-sample cost measured at the largest N
    #: (small launches are dominated by a fixed ~0.05 ms overhead that says nothing of the method)
    seconds: dict[str, np.ndarray] = field(default_factory=dict)
    slope: dict[str, float] = field(default_factory=dict)           #: fitted log-log slope


def convergence_curves(problem=None, methods: Sequence[str] = ("uniform", "cosine", "bsdf",
                                                               "light", "mis"),
                       exponents: Sequence[int] = tuple(range(8, 17, 2)), seeds: int = 16,
                       seed: int = 1) -> ConvergenceCurves:
    """Relative RMSE against N = 2^k for the reflection-equation estimators of
    :mod:`phonglab.estimators` (S seeds per N), the RMSE the per-sample variance predicts,
    the time of one estimate (N × the per-sample cost of the largest launch), and the fitted
    log-log slope (−½ for Monte Carlo)."""
    from ..physics import estimators

    problem = problem or estimators.Problem(diffuse_reflectance=0.2, specular_reflectance=0.7,
                                            exponent=100.0, theta_i=30.0, light="disk",
                                            half_angle=5.0)
    est = estimators.ReflectionEstimators(problem)
    exact = est.exact()
    ns = np.array([2 ** k for k in exponents])
    out = ConvergenceCurves(problem.label, exact, ns)
    for m in methods:
        _, var, _ = est.moments(m, n=1 << 18)
        rmse, times = [], []
        for n in ns:
            e = est.run(m, int(n), seed=seed, batches=seeds)
            rmse.append(float(np.sqrt(np.mean((e.values - exact) ** 2))) / abs(exact))
            times.append(e.seconds / seeds)
        out.rmse[m] = np.array(rmse)
        per = ns / 2 if m == "mis" else ns
        out.predicted[m] = np.sqrt(var / per) / abs(exact)
        out.seconds[m] = ns * (times[-1] / ns[-1])
        good = out.rmse[m] > 0
        out.slope[m] = float(np.polyfit(np.log(ns[good]), np.log(out.rmse[m][good]), 1)[0]) \
            if good.sum() >= 2 else float("nan")
    return out


def fig_convergence(curves: ConvergenceCurves):
    """Left: relative RMSE against N (points) and σ/√N (lines). Right: RMSE against time."""
    fig = _figure(10.0, 4.0)
    ax1, ax2 = fig.subplots(1, 2)
    for k, m in enumerate(curves.rmse):
        color = f"C{k}"
        ax1.loglog(curves.n, curves.rmse[m], "o", color=color,
                   label=f"{m} (slope {curves.slope[m]:.2f})")
        ax1.loglog(curves.n, curves.predicted[m], "-", color=color, alpha=0.6)
        ax2.loglog(curves.seconds[m] * 1e3, curves.rmse[m], "o-", color=color, label=m)
    ax1.set_xlabel("samples N")
    ax1.set_ylabel("relative RMSE")
    ax1.set_title("error falls as N^-1/2 (lines: σ/√N)")
    ax1.legend(fontsize=8)
    ax2.set_xlabel("time per estimate [ms] (N × per-sample cost)")
    ax2.set_ylabel("relative RMSE")
    ax2.set_title("error against time: lower-left wins")
    fig.suptitle(curves.problem_label, fontsize=9)
    return fig


def efficiency_table(curves: ConvergenceCurves) -> list[tuple[str, float, float]]:
    """(method, σ² per sample relative, time-to-equal-error relative to the best method):
    efficiency 1/(σ² t) [Veach 1997, §2.4.3], from the largest N of :func:`convergence_curves`."""
    cost = {m: (curves.rmse[m][-1] ** 2) * curves.seconds[m][-1] for m in curves.rmse}
    best = min(c for c in cost.values() if c > 0) if any(c > 0 for c in cost.values()) else 1.0
    return [(m, float(curves.rmse[m][-1]), float(cost[m] / best)) for m in curves.rmse]


def fig_plan_depths(plan):
    """The planner's depth evidence: relative RMS of the omitted deeper bounces b(d) for each
    pilot depth, the budget 0.25·E it must stay under, and the chosen depth."""
    from ..planner import BIAS_FRACTION

    depths = [d for d in plan.depths if d.depth != -1]
    fig = _figure(5.5, 3.2)
    ax = fig.subplots()
    x = [d.depth for d in depths]
    y = [max(d.bias, 1e-6) for d in depths]
    ax.semilogy(x, y, "o-", label="omitted deeper bounces b(d) (relative RMS)")
    ax.axhline(BIAS_FRACTION * plan.target_error, color="C3", ls="--",
               label=f"budget {BIAS_FRACTION:g} × target error")
    if plan.max_depth != -1:
        ax.axvline(plan.max_depth, color="C2", ls=":", label=f"chosen max_depth {plan.max_depth}")
    ax.set_xlabel("max_depth")
    ax.set_ylabel("relative RMS (floored at 1e-6)")
    ax.set_title(f"{Path(plan.scene).name}: pilot at {plan.pilot_spp} spp", fontsize=9)
    ax.legend(fontsize=7)
    return fig


def write_doc_images(folder: str | Path = "docs/img", dpi: int = 72) -> list[Path]:
    """The one figure per notebook that docs/notebooks.md shows, as ``nb_*.png``
    (``make notebook-figures``); the same calls, at the same default sample counts, as the
    notebooks make."""
    folder = Path(folder)
    _register()
    rows = {"plastic: red k_d, grey k_s": render_sphere_row(16, **PLASTIC),
            "metal: k_d ≈ 0, coloured k_s": render_sphere_row(16, **METAL)}
    figs = {
        "nb_01_radiance_constancy.png": fig_emitter_distances(emitter_distance_series(spp=4)),
        "nb_01_reflection_equation.png": fig_reflection_equation(),
        "nb_02_sphere_rows.png": fig_sphere_rows(rows),
        "nb_02_furnace.png": fig_albedo(albedo_curves(samples=20000)),
        "nb_03_refraction.png": fig_refraction_agreement(refraction_agreement()),
        "nb_04_convergence.png": fig_convergence(convergence_curves(seeds=8)),
    }
    return [save(fig, folder / name, dpi=dpi) for name, fig in figs.items()]
