r"""Notebook 05 (fitting Phong to physics): lobe cuts, albedo and residual, image fits.

:func:`lobe_cuts` + :func:`fig_lobe_cuts` (target against fitted phong in the plane of
incidence, from both plugins' ``eval``), :func:`fig_fit_albedo` (a :class:`FitResult`'s albedo
and residual against θ_i), :func:`fig_image_fit` and :func:`fig_image_history` (an
:class:`~phonglab.fit.render_fit.ImageFit`).  The fits live in :mod:`phonglab.fit`; this
module only arranges and plots their numbers.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from .. import probe
from ..fit.objective import PHONG
from ..fit.optimize import FitResult, load_target
from ..engine.metrics import LUMINANCE
from ..engine.tonemap import to_srgb
from .common import figure, load_bsdf


def lobe_cuts(result: FitResult, thetas_deg: Sequence[float] = (0.0, 45.0, 75.0),
              n: int = 721) -> tuple[np.ndarray, dict[float, tuple[np.ndarray, np.ndarray]]]:
    """f_r cos θ_o (luminance) of target and fitted phong in the plane of incidence.

    Returns (θ_o in radians, −π/2 … π/2, positive on the mirror side; {θ_i: (target, fit)}).
    """
    target = load_target(result.target, result.target_params)
    kd, ks, p = result.fitted if result.model == "phong" else (result.fitted[0], 0.0, 1.0)
    fitted = load_bsdf("phong", diffuse_reflectance=kd, specular_reflectance=ks, exponent=p)
    t = np.linspace(-math.pi / 2, math.pi / 2, n)
    wo = probe.direction(t)
    out = {}
    for ti in thetas_deg:
        wi = probe.direction(math.radians(ti), math.pi)
        out[float(ti)] = (probe.eval(target, wi, wo) @ LUMINANCE, probe.eval(fitted, wi, wo) @ LUMINANCE)
    return t, out


def fig_lobe_cuts(result: FitResult, thetas_deg: Sequence[float] = (0.0, 45.0, 75.0)):
    """One panel per incidence angle: target (black) and fitted phong (orange), linear scale."""
    t, cuts = lobe_cuts(result, thetas_deg)
    fig = figure(3.2 * len(cuts), 2.8)
    axes = np.atleast_1d(fig.subplots(1, len(cuts)))
    for ax, (ti, (g_t, g_m)) in zip(axes, cuts.items()):
        deg = np.degrees(t)
        ax.plot(deg, g_t, color="k", label=result.target)
        ax.plot(deg, g_m, color="C1", ls="--", label=result.model)
        ax.axvline(ti, color="0.6", lw=0.8, ls=":")
        ax.set_xlabel("θ_o [deg] (mirror side > 0)")
        ax.set_title(f"θ_i = {ti:g}°", fontsize=9)
    axes[0].set_ylabel("f_r cos θ_o (luminance)")
    axes[0].legend(fontsize=7)
    return fig


def fig_fit_albedo(result: FitResult):
    """Albedo of fit and target, and the residual r(θ_i), against the incidence angle."""
    fig = figure(8.0, 3.0)
    a, b = fig.subplots(1, 2)
    deg = result.report_deg
    a.plot(deg, result.albedo_target, "o-", color="k", label=result.target)
    a.plot(deg, result.albedo_fit, "s--", color="C1", label=f"fitted {result.model}")
    a.set_ylim(0, 1.05)
    a.set_xlabel("θ_i [deg]")
    a.set_ylabel("directional albedo")
    a.legend(fontsize=7)
    b.plot(deg, result.residual, "o-", color="C3")
    b.set_xlabel("θ_i [deg]")
    b.set_ylabel("relative residual r(θ_i)")
    b.set_ylim(bottom=0)
    fig.suptitle(f"{result.model} fitted to {result.target} {result.target_params}: "
                 f"relative L2 {result.rel_l2:.3f}", fontsize=9)
    return fig


def fig_image_fit(images: dict[str, np.ndarray]):
    """Images side by side (label → (H, W, 3) linear RGB), same exposure, and |fit − target|."""
    labels = list(images)
    fig = figure(2.4 * (len(labels) + 1), 2.6)
    axes = fig.subplots(1, len(labels) + 1)
    for ax, label in zip(axes, labels):
        ax.imshow(to_srgb(images[label]), interpolation="nearest")
        ax.set_title(label, fontsize=8)
    diff = np.abs(images[labels[-1]] - images[labels[0]]).mean(axis=-1)
    im = axes[-1].imshow(diff, cmap="magma", interpolation="nearest")
    axes[-1].set_title(f"|{labels[-1]} − {labels[0]}|", fontsize=8)
    fig.colorbar(im, ax=axes[-1], shrink=0.8)
    for ax in axes:
        ax.set_xticks([])
        ax.set_yticks([])
    return fig


def fig_image_history(fit, truth: Sequence[float] | None = None):
    """The loss and the parameters (k_d, k_s, p) of an image fit against the iteration."""
    fig = figure(9.0, 2.6)
    axes = fig.subplots(1, 4)
    axes[0].semilogy(fit.losses, color="k")
    axes[0].set_title("loss (mean squared pixel error)", fontsize=8)
    history = np.array(fit.history)
    for k, (ax, label) in enumerate(zip(axes[1:], PHONG.labels)):
        ax.plot(history[:, k], color=f"C{k}")
        if truth is not None:
            ax.axhline(truth[k], color="k", ls=":", lw=0.8, label="truth")
            ax.legend(fontsize=7)
        ax.set_title(f"{label}: fitted {fit.fitted[k]:.3g}", fontsize=8)
    for ax in axes:
        ax.set_xlabel("Adam iteration", fontsize=8)
    return fig
