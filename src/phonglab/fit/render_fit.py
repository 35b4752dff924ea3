r"""The fit from images: phong parameters recovered by differentiable rendering (``prb``).

The scene (:func:`sphere_scene`): a unit sphere seen by a pinhole camera, lit by two point
lights (one near the camera, one from the side, so both normal and grazing configurations
appear on the sphere) and a dim constant environment; ``prb`` (Mitsuba's path-replay
backpropagation integrator, the one its docs recommend for material optimization) with
max_depth 2, which is exact for a convex object (no interreflection).  A target image is
rendered with the target BSDF; then the ``phong`` plugin takes the sphere's place and its
parameters are fitted with ``mi.ad.Adam`` to the mean squared pixel difference.

Parametrization as in :mod:`.objective` (x = (t, s, q), k_d = t(1 − s), k_s = t s,
p = exp q), with projected steps: after each Adam step x is clipped to the box, so every
image is rendered with k_d + k_s ≤ 1.  Every fit render uses the same seed (common random
numbers) would make the loss deterministic, but at small resolutions the fit then follows
that one seed's aliasing of the highlight; instead each iteration renders with fresh seeds,
the primal and the adjoint pass with independent ones (``seed_grad``), so the gradient is an
unbiased estimate of the gradient of |E[image] − target|², and the result is the mean of
the last iterates (Polyak averaging).

Noise.  The target's pixel noise ε (variance σ_T², measured from independent renders by
:func:`pixel_variance`) moves the minimizer of |E[image](x) − target|² by
(JᵀJ)⁻¹Jᵀ ε to first order, J = ∂image/∂x (forward-mode AD through ``prb``,
:func:`jacobian`), so Cov(x̂) = (JᵀJ)⁻¹Jᵀ diag(σ_T²) J (JᵀJ)⁻¹ (:func:`parameter_covariance`);
the stochastic optimizer adds the standard error of its averaged iterates (batch means,
:func:`batch_means_se`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import drjit as dr
import mitsuba as mi
import numpy as np

from .objective import PHONG

#: ``mi.traverse`` keys of the sphere's phong parameters.
KEYS = ("sphere.bsdf.diffuse_reflectance.value", "sphere.bsdf.specular_reflectance.value",
        "sphere.bsdf.exponent")


def sphere_scene(bsdf: dict, res: int = 32):
    """The fitting scene with ``bsdf`` (a ``mi.load_dict`` dict) on the sphere."""
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "prb", "max_depth": 2},
        "sensor": {"type": "perspective", "fov": 32.0,
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 4.2], target=[0, 0, 0],
                                                              up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": res, "height": res,
                            "rfilter": {"type": "box"}, "pixel_format": "rgb"}},
        "sphere": {"type": "sphere", "bsdf": bsdf},
        "key": {"type": "point", "position": [1.5, 1.5, 4.0], "intensity": {"type": "rgb",
                                                                            "value": [12.0] * 3}},
        "rim": {"type": "point", "position": [-4.0, 0.5, -0.5], "intensity": {"type": "rgb",
                                                                              "value": [10.0] * 3}},
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [0.1] * 3}},
    })


def phong_dict(kd: float, ks: float, p: float) -> dict:
    return {"type": "phong", "diffuse_reflectance": kd, "specular_reflectance": ks,
            "exponent": p}


def render(scene, spp: int, seed: int = 0, params=None) -> np.ndarray:
    """One render as numpy (H, W, 3)."""
    return np.array(mi.render(scene, params, spp=spp, seed=seed), dtype=np.float64)


def pixel_variance(scene, spp: int, renders: int = 8, seed: int = 1000) -> np.ndarray:
    """Per-pixel variance (H, W, 3) of an spp render, from ``renders`` independent seeds."""
    images = np.stack([render(scene, spp, seed + k) for k in range(renders)])
    return images.var(axis=0, ddof=1)


def _set(params, x) -> None:
    for key, value in zip(KEYS, PHONG.physical(x)):
        params[key] = value
    params.update()


def _box(x: np.ndarray) -> np.ndarray:
    lo, hi = np.array(PHONG.bounds).T
    return np.clip(np.asarray(x, dtype=np.float64), lo, hi)


def jacobian(scene, x, spp: int, seed: int = 0) -> np.ndarray:
    """J = ∂image/∂x, (pixels·3, 3), by forward-mode AD through the integrator."""
    params = mi.traverse(scene)
    cols = []
    for k in range(3):
        xs = [dr.opaque(mi.Float, float(v)) for v in _box(x)]
        dr.enable_grad(xs[k])
        _set(params, xs)
        img = mi.render(scene, params, spp=spp, seed=seed)
        dr.forward(xs[k])
        cols.append(np.array(dr.grad(img), dtype=np.float64).ravel())
    with dr.suspend_grad():
        _set(params, [dr.opaque(mi.Float, float(v)) for v in _box(x)])
    return np.stack(cols, axis=1)


def parameter_covariance(J: np.ndarray, variance: np.ndarray) -> np.ndarray:
    """(JᵀJ)⁻¹ Jᵀ diag(σ²) J (JᵀJ)⁻¹: the covariance of least-squares x̂ under pixel noise σ²."""
    A = np.linalg.inv(J.T @ J)
    return A @ (J.T * variance.ravel()) @ J @ A


@dataclass
class ImageFit:
    """An image-based fit: the fitted parameters, the loss history and the images."""

    start: list
    fitted: list
    x: np.ndarray
    gradient: np.ndarray
    batch_se: np.ndarray | None = None
    losses: list = field(default_factory=list)
    history: list = field(default_factory=list)     #: physical parameters per iteration
    image: np.ndarray | None = None


def batch_means_se(samples: np.ndarray, batches: int = 5) -> np.ndarray:
    """Standard error of the mean of correlated iterates (rows) by the method of batch means."""
    means = np.array([b.mean(axis=0) for b in np.array_split(samples, batches)])
    return means.std(axis=0, ddof=1) / np.sqrt(batches)


def fit_image(target: np.ndarray, start, res: int = 32, spp: int = 16, iterations: int = 150,
              lr: float = 0.05, seed: int = 0, average: int = 50,
              image_spp: int | None = None) -> ImageFit:
    """Fit phong to ``target`` (H, W, 3) with mi.ad.Adam from ``start`` = (k_d, k_s, p).

    Every iteration renders with fresh seeds; the learning rate decays as
    lr / (1 + 4 i / iterations) and the result is the mean of the last ``average`` iterates
    (in x), whose standard error ``batch_se`` comes from batch means.  ``image`` is the fitted
    phong rendered at ``image_spp`` (default 16 spp) with another seed.
    """
    scene = sphere_scene(phong_dict(*start), res)
    params = mi.traverse(scene)
    ref = mi.TensorXf(np.asarray(target, dtype=np.float32))
    opt = mi.ad.Adam(lr=lr)
    for k, v in enumerate(PHONG.variables(start)):
        opt[f"x{k}"] = mi.Float(float(v))
    out = ImageFit(list(start), [], np.zeros(3), np.zeros(3))
    for i in range(iterations):
        opt.set_learning_rate(lr / (1.0 + 4.0 * i / iterations))
        _set(params, [opt[f"x{k}"] for k in range(3)])
        # Primal and adjoint from independent samples: an unbiased gradient of |E[image] - target|².
        img = mi.render(scene, params, spp=spp, seed=seed + 2 * i, seed_grad=seed + 2 * i + 1)
        loss = dr.mean(dr.square(img - ref), axis=None)
        dr.backward(loss)
        out.gradient = np.array([float(dr.grad(opt[f"x{k}"])[0]) for k in range(3)])
        opt.step()
        lo, hi = np.array(PHONG.bounds).T
        for k in range(3):   # projected step: stay in the energy-conserving box
            opt[f"x{k}"] = dr.clip(opt[f"x{k}"], float(lo[k]), float(hi[k]))
        out.losses.append(float(loss.array[0]))
        out.history.append([float(v) for v in PHONG.physical(
            [float(opt[f"x{k}"][0]) for k in range(3)])])
    tail = np.array([PHONG.variables(h) for h in out.history[-average:]])
    out.x = _box(tail.mean(axis=0))
    out.batch_se = batch_means_se(tail)
    out.fitted = [float(v) for v in PHONG.physical(out.x)]
    with dr.suspend_grad():
        _set(params, [dr.opaque(mi.Float, float(v)) for v in out.x])
        out.image = render(scene, image_spp or 16 * spp, seed + 2 * iterations)
    return out
