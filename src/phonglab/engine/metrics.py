r"""Image error metrics: one definition of each, used by compare, render, the planner and bench.

With x the image under test, r the reference, per value (pixel i, channel c),
``d = x − r``, and means over every pixel and channel:

* RMSE                  = √mean(d²)
* relative MSE (relMSE) = mean(d² / (r² + ε)),  ε = :data:`REL_EPS` = 10⁻²
* relative RMSE         = √relMSE: **the** relative error of phonglab (the planner's error
  target E, ``render --target-error``, the bench's error axes).

The relMSE is the rendering literature's (Rousselle, Knaus & Zwicker, "Adaptive sampling and
reconstruction using greedy error minimization", SIGGRAPH Asia 2011; Bitterli's and Mitsuba's
benchmarks use the same form); ε keeps black pixels from dominating: a pixel of radiance
well above √ε = 0.1 counts with its relative error, a darker one with its absolute error
/ 0.1.

A reference rendered by Monte Carlo carries its own noise, standard error s_r per value:
E[d²] = MSE_true + s_r², so passing ``ref_stderr`` subtracts mean(s_r² / (r² + ε)) (and
mean(s_r²) from the MSE), clamped at 0 (:func:`errors`).

**The error target E** (``--target-error E`` of ``phonglab plan`` and ``phonglab render``,
:class:`phonglab.planner.PlanOptions`; the one definition, which the others refer to) is the
*total* relative RMSE of the image
against a converged reference r: the image at unbounded depth (``max_depth = -1``, paths ended
by Russian roulette, no depth bias; :func:`phonglab.engine.references.reference`), its own noise
subtracted as above.  Its square splits into bias and noise, E² = b² + n² (MSE = bias² +
variance: Veach, PhD thesis, Stanford 1997, §2.4.3), with b the relative RMS of what the
render leaves out systematically (the energy of the bounces past a finite max_depth: the
planner's depth bias b(d), :mod:`phonglab.planner`) and n its relative noise
(:func:`relative_noise`).  A render that stops on its own noise estimate therefore aims its
noise at :func:`noise_target` (E, b) = √(E² − b²):

* ``render --target-error E`` (planned) has b from the pilot: a uniform render takes the spp
  with b² + n² <= E², a wavefront one (another model, adaptive sampling) aims at √(E² − b²);
* ``render --adaptive --target-noise N`` (:func:`phonglab.engine.adaptive.render_adaptive`) has
  no bias estimate: N is a noise target, the relative noise the render may leave.  N is its
  total error only when the render is unbiased against the reference (the scene's integrator
  at ``max_depth = -1``, or at a depth past which the scene carries no energy); at a finite
  depth that omits energy the total error is about √(N² + b²), b the depth bias of that
  max_depth (``phonglab plan SCENE --max-depth D`` gives b(D) in its reasons).

Both targets are checked by :func:`check_target`.

**Luminance** is Rec. 709 / sRGB, with the coefficients Mitsuba's ``mi.luminance`` and its
mono variants use: Y = 0.212671 R + 0.715160 G + 0.072169 B.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import CompareError
from ..settings import ParameterError

#: ε of the relative MSE: d² / (r² + REL_EPS).
REL_EPS = 1e-2
#: Rec. 709 luminance weights of linear R, G, B (as mi.luminance and Mitsuba's mono variants).
LUMINANCE = np.array([0.212671, 0.715160, 0.072169])


def as_hwc(image, name: str = "image") -> np.ndarray:
    """An (H, W) or (H, W, C) image as float64 (H, W, C)."""
    a = np.asarray(image, dtype=np.float64)
    if a.ndim == 2:
        a = a[..., None]
    if a.ndim != 3:
        raise CompareError(f"{name} has shape {a.shape}; give an (H, W) or (H, W, C) image")
    return a


def luminance(image, keepdims: bool = False) -> np.ndarray:
    """Rec. 709 luminance of a linear (H, W, 3) image; a one-channel image is returned as is.

    Returns (H, W), or (H, W, 1) with ``keepdims``.
    """
    a = as_hwc(image)
    y = a[..., :3] @ LUMINANCE if a.shape[2] >= 3 else a[..., 0]
    return y[..., None] if keepdims else y


def match_channels(image, reference) -> tuple[np.ndarray, np.ndarray]:
    """Both images as (H, W, C) with equal C: an RGB image meets a mono one as its luminance."""
    a, b = as_hwc(image, "the image"), as_hwc(reference, "the reference")
    if a.shape[2] != b.shape[2]:
        a, b = luminance(a, keepdims=True), luminance(b, keepdims=True)
    if a.shape != b.shape:
        raise CompareError(f"cannot compare images of shapes {a.shape} and {b.shape}; render "
                           f"the reference at the same resolution")
    return a, b


def rmse(image, reference) -> float:
    """√mean((x − r)²)."""
    d = as_hwc(image) - as_hwc(reference)
    return float(np.sqrt(np.mean(d * d)))


def rel_mse(image, reference, eps: float = REL_EPS, ref_stderr=None) -> float:
    """mean((x − r)² / (r² + ε)), less the reference's own noise when ``ref_stderr`` is given."""
    return errors(image, reference, ref_stderr, eps)["rel_mse"]


def relative_rmse(image, reference, eps: float = REL_EPS, ref_stderr=None) -> float:
    """√relMSE: phonglab's relative error (see the module docstring)."""
    return math.sqrt(max(rel_mse(image, reference, eps, ref_stderr), 0.0))


def relative_noise(image, stderr, eps: float = REL_EPS) -> float:
    """√mean(s² / (x² + ε)): the relative error that a per-pixel standard error s amounts to."""
    x, s = match_channels(image, stderr)
    return math.sqrt(float(np.mean(s * s / (x * x + eps))))


def noise_target(total_error: float, bias: float = 0.0) -> float:
    """√(E² − b²): the relative noise a render may leave to reach the total relative error E
    with a relative bias b (module docstring), at least E/100 (where b alone reaches E the
    render cannot meet E, and a smaller noise target would only cost samples)."""
    return math.sqrt(max(total_error ** 2 - bias ** 2, (0.01 * total_error) ** 2))


def check_target(value, what: str = "the target error") -> float:
    """A relative RMSE to reach (E, or a noise target) as a float in (0, 10), else
    :class:`phonglab.settings.ParameterError` in one sentence: the one check of both targets."""
    if not (isinstance(value, (int, float)) and math.isfinite(value) and 0 < value < 10):
        raise ParameterError(f"{what} must be a relative RMSE in (0, 10), e.g. 0.01 for 1 %, "
                             f"got {value!r}")
    return float(value)


def errors(image, reference, ref_stderr=None, eps: float = REL_EPS) -> dict[str, float]:
    """RMSE, MSE, relMSE (reference noise removed when ``ref_stderr`` is given) and NaN count.

    An RGB image against a mono reference (or the reverse) is compared in luminance.
    Non-finite values of the image are counted (``nan_count``) and left out of the means.
    """
    x, r = match_channels(image, reference)
    finite = np.isfinite(x)
    d2 = np.where(finite, (x - r) ** 2, 0.0)
    if ref_stderr is not None:
        _, s = match_channels(x, ref_stderr)
        d2 = np.where(finite, d2 - s * s, 0.0)
    n = max(int(finite.sum()), 1)
    mse = float(d2.sum() / n)
    rel = float(np.sum(d2 / (r * r + eps)) / n)
    return {"rmse": math.sqrt(max(mse, 0.0)), "mse": mse, "rel_mse": rel,
            "relative_rmse": math.sqrt(max(rel, 0.0)), "nan_count": int((~finite).sum())}
