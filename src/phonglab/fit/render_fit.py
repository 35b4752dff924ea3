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

Noise.  The target's pixel noise ε (per-pixel RGB covariance C_T, measured from independent
renders by :func:`pixel_covariance`) moves the minimizer of |E[image](x) − target|² by
(JᵀJ)⁻¹Jᵀ ε to first order, J = ∂image/∂x (forward-mode AD through ``prb``,
:func:`jacobian`), so Cov(x̂) = (JᵀJ)⁻¹ Jᵀ C_T J (JᵀJ)⁻¹ (:func:`parameter_covariance`);
Adam stops short along the valley k_s (p + 2) ≈ const, so Gauss–Newton steps with J and a
render at x̂ finish the fit (:func:`gauss_newton_step`); after the last one the covariance is
the same expression with C_T + C_P (C_P the noise of that render), to first order.
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


def pixel_covariance(scene, spp: int, renders: int = 8, seed: int = 1000) -> np.ndarray:
    """Per-pixel 3 x 3 covariance of the RGB noise of an spp render, (H, W, 3, 3), from
    ``renders`` independent seeds.  The channels of a pixel share their paths, so their noise
    is correlated (identical in a grey scene): a per-channel variance alone would understate
    the parameters' noise by up to √3."""
    images = np.stack([render(scene, spp, seed + k) for k in range(renders)])
    dev = images - images.mean(axis=0)
    return np.einsum("khwc,khwd->hwcd", dev, dev) / (renders - 1)


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


def parameter_covariance(J: np.ndarray, covariance: np.ndarray) -> np.ndarray:
    """(JᵀJ)⁻¹ (Σ_pixels J_pᵀ C_p J_p) (JᵀJ)⁻¹: the covariance of least-squares x̂ under pixel
    noise with per-pixel channel covariance C_p ((H, W, 3, 3), :func:`pixel_covariance`);
    J is (pixels·3, 3) as :func:`jacobian` returns it."""
    A = np.linalg.inv(J.T @ J)
    Jp = J.reshape(-1, 3, J.shape[1])                      # (pixel, channel, parameter)
    M = np.einsum("pci,pcd,pdj->ij", Jp, covariance.reshape(-1, 3, 3), Jp)
    return A @ M @ A


@dataclass
class ImageFit:
    """An image-based fit: the fitted parameters, the loss history and the images."""

    start: list
    fitted: list
    x: np.ndarray
    gradient: np.ndarray
    batch_se: np.ndarray | None = None
    x_adam: np.ndarray | None = None                #: Adam's averaged iterates, before polishing
    losses: list = field(default_factory=list)
    history: list = field(default_factory=list)     #: physical parameters per iteration
    image: np.ndarray | None = None


def batch_means_se(samples: np.ndarray, batches: int = 5) -> np.ndarray:
    """Standard error of the mean of correlated iterates (rows) by the method of batch means."""
    means = np.array([b.mean(axis=0) for b in np.array_split(samples, batches)])
    return means.std(axis=0, ddof=1) / np.sqrt(batches)


def learning_rate(i: int, iterations: int, lr: float, final: float) -> float:
    """lr for the first half of the iterations, then falling geometrically to ``final`` x lr.

    Adam's steps have the size of the learning rate whatever the gradient's noise, so the
    iterates jitter by about that much around the optimum; the fall makes that jitter small
    against the target's noise before the iterates are averaged.
    """
    return lr * final ** max(0.0, 2.0 * i / iterations - 1.0)


def gauss_newton_step(scene, x, target: np.ndarray, spp: int, seed: int) -> np.ndarray:
    """x − (JᵀJ)⁻¹Jᵀ(image(x) − target), J by forward-mode AD and the image at ``spp``, in the box."""
    J = jacobian(scene, x, spp, seed)
    with dr.suspend_grad():
        _set(mi.traverse(scene), [dr.opaque(mi.Float, float(v)) for v in _box(x)])
        residual = (render(scene, spp, seed + 1) - target).ravel()
    return _box(np.asarray(x) - np.linalg.lstsq(J, residual, rcond=None)[0])


def fit_image(target: np.ndarray, start, res: int = 32, spp: int = 16, iterations: int = 100,
              lr: float = 0.05, seed: int = 0, average: int = 30, final_lr: float = 0.1,
              polish_spp: int = 256, polish_steps: int = 2) -> ImageFit:
    """Fit phong to ``target`` (H, W, 3) with mi.ad.Adam from ``start`` = (k_d, k_s, p).

    Every Adam iteration renders with fresh seeds; the learning rate follows
    :func:`learning_rate`; ``x_adam`` is the mean of the last ``average`` iterates (in x, with
    the batch-means standard error ``batch_se``).  Adam creeps along the ill-conditioned
    valley k_s (p + 2) ≈ const (the highlight's peak), so ``polish_steps`` Gauss–Newton steps
    (:func:`gauss_newton_step`, renders at ``polish_spp``) finish the fit: after the last one
    the error is, to first order, the least-squares response to the target's noise and the
    last polish render's noise alone (:func:`parameter_covariance` with C_T + C_P).
    ``image`` is the fitted phong rendered at ``polish_spp``.
    """
    scene = sphere_scene(phong_dict(*start), res)
    out = _adam(scene, target, start, spp, iterations, lr, final_lr, seed)
    tail = np.array([PHONG.variables(h) for h in out.history[-average:]])
    out.x_adam = _box(tail.mean(axis=0))
    out.batch_se = batch_means_se(tail)
    out.x = out.x_adam
    for k in range(polish_steps):
        out.x = gauss_newton_step(scene, out.x, target, polish_spp, seed + 2 * iterations + 2 * k)
    out.fitted = [float(v) for v in PHONG.physical(out.x)]
    with dr.suspend_grad():
        _set(mi.traverse(scene), [dr.opaque(mi.Float, float(v)) for v in out.x])
        out.image = render(scene, polish_spp, seed + 2 * iterations + 2 * polish_steps)
    return out


def _adam(scene, target, start, spp, iterations, lr, final_lr, seed) -> ImageFit:
    """The Adam loop of :func:`fit_image` (projected steps, fresh seeds, seed_grad)."""
    params = mi.traverse(scene)
    ref = mi.TensorXf(np.asarray(target, dtype=np.float32))
    opt = mi.ad.Adam(lr=lr)
    for k, v in enumerate(PHONG.variables(start)):
        opt[f"x{k}"] = mi.Float(float(v))
    out = ImageFit(list(start), [], np.zeros(3), np.zeros(3))
    lo, hi = np.array(PHONG.bounds).T
    for i in range(iterations):
        opt.set_learning_rate(learning_rate(i, iterations, lr, final_lr))
        _set(params, [opt[f"x{k}"] for k in range(3)])
        # Primal and adjoint from independent samples: an unbiased gradient of |E[image] - target|².
        img = mi.render(scene, params, spp=spp, seed=seed + 2 * i, seed_grad=seed + 2 * i + 1)
        loss = dr.mean(dr.square(img - ref), axis=None)
        dr.backward(loss)
        out.gradient = np.array([float(dr.grad(opt[f"x{k}"])[0]) for k in range(3)])
        opt.step()
        for k in range(3):   # projected step: stay in the energy-conserving box
            opt[f"x{k}"] = dr.clip(opt[f"x{k}"], float(lo[k]), float(hi[k]))
        out.losses.append(float(loss.array[0]))
        out.history.append([float(v) for v in PHONG.physical(
            [float(opt[f"x{k}"][0]) for k in range(3)])])
    return out
