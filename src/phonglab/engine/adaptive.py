r"""Adaptive sampling: passes that trace rays only for the pixels whose error exceeds its budget.

Mitsuba's ``mi.render`` renders the whole film with one sample count.  :func:`render_adaptive`
runs its own Dr.Jit wavefront instead: per pass, a numpy count ``n_p`` of new samples for each
pixel p becomes one index array (``np.repeat`` of the active pixel indices, one lane per sample;
pixels with ``n_p = 0`` cost nothing), and for those lanes it does what Mitsuba's
``SamplingIntegrator::render`` does per sample: a position ``p + U²`` in the pixel, a ray from
``sensor.sample_ray_differential`` (time, wavelength and aperture samples as Mitsuba draws
them), ``integrator.sample(scene, sampler, ray, medium, active)`` (``path``, ``direct``,
phonglab's ``whitted``, any sampling integrator), times the ray weight.  Spectral variants
convert each sample to linear sRGB (``mi.spectrum_to_srgb``, linear, so the mean commutes),
polarized ones keep the unpolarized part; mono films have one channel (alpha and AOVs are not
written).  Samples come from an ``independent`` sampler seeded per pass with
:func:`phonglab.engine.render.pass_seed` (seed, k) and the wavefront size, whatever sampler the scene
names: the samples of a pixel are then i.i.d., which the variance estimate below needs.

**Two accumulations per sample.**  (1) The image: ``mi.ImageBlock`` with the film's own
reconstruction filter (``put`` of the colour and a weight channel 1), so pixel p is
``x_p = Σ_s w_ps f_s / Σ_s w_ps`` exactly as the film develops it and the image is comparable
with ``mi.render``'s and with the cached references.  (2) Box moments per pixel (each sample to
its own pixel, ``dr.scatter_reduce``): ``N_q``, ``S1_q = Σ f``, ``S2_q = Σ f²`` (float64 on the
host across passes).

**Per-pixel error (honest, from the samples themselves).**  The filtered value is a ratio of
sums of i.i.d. terms, so (delta method) its variance is

    Var x_p ≈ Σ_q B_{q−p} · Σ_{s∈q} (f_s − x_p)² / (Σ_q A_{q−p} N_q)²,
    Σ_{s∈q} (f_s − x_p)² = S2_q − 2 x_p S1_q + x_p² N_q,

with ``A_d = a(d_x) a(d_y)``, ``B_d = b(d_x) b(d_y)``, ``a(d) = ∫₀¹ w(u − ½ − d) du`` and
``b(d) = ∫₀¹ w(u − ½ − d)² du`` the pixel integrals of the (separable) filter w
(:func:`filter_tables`), assuming a sample's position within its pixel is independent of its
value.  For the box filter this is the textbook variance of the mean of the pixel's own
samples.  It is scaled by ``D²/(D² − Σ A² N)`` (D the denominator; N/(N−1) for a box: the
unbiased sample variance).  Per-sample moments, not the spread of pass images: every sample
count is an integer, passes of one pixel differ in size, and the moments give N − 1 degrees
of freedom instead of passes − 1.  The relative error of pixel p is
``e_p² = mean_c Var x_pc / (x_pc² + ε)`` (ε = :data:`phonglab.engine.metrics.REL_EPS`, the project's
relative MSE).

**Target and allocation.**  The target E is the image's relative RMSE against a converged
reference, √mean_pc((x − r)²/(r² + ε)) (:func:`phonglab.engine.metrics.relative_rmse`), as far as
noise makes it: the renderer has no depth-bias estimate, so E is the total error only for an
unbiased render (:mod:`phonglab.engine.metrics`, the one definition of E; the planner passes
√(E² − b²)).  Its square is the mean of the ``e_p²``.  With ``v_p = e_p² N_p`` (relative
variance of one sample), minimising Σ N_p subject to mean_p v_p/N_p = E² (Lagrange) gives
``N_p* = √v_p · mean_q √v_q / E²`` — each pixel's budget is ``e_p*² = v_p/N_p* =
E² √v_p / mean √v``: noisy pixels are allowed more error, quiet ones less, and the mean meets
E².  A pass adds ``min(N_p* − N_p, (GROWTH − 1)·N_p)`` samples to each pixel below N_p*
(re-estimated every pass, so a noisy pilot estimate cannot overshoot far); the render stops
when the estimated image error √mean e_p² <= E, when no pixel is below N_p*, or at a cap.

**Guards against pixels that only look converged** (no sample has found the light yet):
every pixel gets the pilot's :data:`MIN_SPP` samples, and the allocation is shaped by
``g_p = max(v_p, mean of v over the window)`` (:data:`NEIGHBOURHOOD`), so a pixel whose
own samples show no variance inherits its neighbours', while its size is set by the
estimates v themselves: ``N_p* = √g_p · mean(v/√g) / E²`` predicts exactly E² (sized by g,
the guard made renders stop 13–22 % below E with a third more samples; :func:`allocation`).
(The window's *max* would inflate a uniform-variance image's budget by the noise of nine
estimates; the mean is unbiased there.)
The bench (:mod:`phonglab.bench.adaptive_sweeps`) measures what they do: the fraction of
pixels whose true error exceeds three times their budget against a converged reference, with
and without the neighbourhood rule.

Sources: Mitsuba 3 ``src/render/integrator.cpp`` (``SamplingIntegrator::render_sample``: ray
generation) and ``src/render/imageblock.cpp`` (``ImageBlock::put``); Rousselle, Knaus &
Zwicker 2011 (relative MSE, adaptive sampling); Pharr, Jakob & Humphreys, *PBRT* 4th ed.
§2.1.4 (variance of the mean) and §8.8 (filtering); the optimal allocation N ∝ σ is the
Neyman allocation of stratified sampling (Cochran, *Sampling Techniques*, 3rd ed., §5.5).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import drjit as dr
import mitsuba as mi
import numpy as np

from . import exr
from ..errors import PhonglabError
from .metrics import REL_EPS
from .outputs import spp_paths
from .render import MAX_SPP, film_channels, pass_seed, preflight, render_scene_file
from ..runtime import default_variant, require_memory
from ..settings import check_max_seconds
from .spp_map import spp_map_image

#: Samples every pixel gets in the pilot pass (the first guard).
MIN_SPP = 16
#: Half-width of the window of the neighbourhood guard (2: 5×5).
NEIGHBOURHOOD = 2
#: A pass at most multiplies a pixel's sample count by this.
GROWTH = 4
#: Most samples one wavefront traces (larger passes are split into several launches).
MAX_WAVEFRONT = 1 << 24
#: Bytes per pixel and filter offset: float32 filter sums of C + 1 channels, kept in the
#: JIT backend's memory (host memory on LLVM), with temporaries (25 offsets for the gaussian
#: filter: about 1 KiB a pixel, 1 GiB at 1024²).
HOST_BYTES_PER_PIXEL_OFFSET = 40


@dataclass
class AdaptiveResult:
    """An adaptive render: image, its per-pixel standard error, the spp map and the passes."""

    image: np.ndarray            #: (H, W, C) float32, filtered with the film's filter
    stderr: np.ndarray           #: (H, W, C) float32 standard error of each pixel value
    spp: np.ndarray              #: (H, W) int64 samples traced in each pixel
    seconds: float               #: wall time of all passes (the first includes JIT compile)
    target_error: float
    estimated_error: float       #: √mean e_p² at the end (the estimate the stop uses)
    stopped: str                 #: 'target', 'max_spp' or 'max_seconds'
    passes: list[dict[str, Any]] = field(default_factory=list)  #: per pass: pixels, samples, s
    metadata: dict[str, Any] = field(default_factory=dict)

    @property
    def total_spp(self) -> float:
        """Mean samples per pixel."""
        return float(self.spp.mean())


def filter_integrals(rfilter, samples: int = 64) -> tuple[np.ndarray, np.ndarray]:
    """(a, b) on offsets d = −R..R: ``a(d) = ∫₀¹ w(u − ½ − d) du`` and ``b(d) = ∫₀¹ w(...)² du``
    (midpoint rule, ``samples`` points), the mean weight (and squared weight) a sample
    anywhere in pixel q gives pixel p = q + d along one axis of a separable filter w."""
    radius = int(math.ceil(float(rfilter.radius()) + 0.5))
    d = np.arange(-radius, radius + 1, dtype=np.float64)
    u = (np.arange(samples) + 0.5) / samples
    x = (u[None, :] - 0.5 - d[:, None]).ravel()
    w = np.array(rfilter.eval(mi.Float(x)), dtype=np.float64).reshape(len(d), samples)
    return w.mean(axis=1), (w * w).mean(axis=1)


def filter_tables(rfilter, samples: int = 64) -> tuple[np.ndarray, np.ndarray]:
    """(A, B) = (a ⊗ a, b ⊗ b) of :func:`filter_integrals`, indexed [d_y + R, d_x + R]."""
    a, b = filter_integrals(rfilter, samples)
    return np.outer(a, a), np.outer(b, b)


def separable_filter(kernel: np.ndarray, a: np.ndarray) -> np.ndarray:
    """``a`` (H, W, ...) convolved with the separable kernel k ⊗ k over its first two axes,
    zero outside the image: one shifted, weighted slice per tap and axis.  (numpy alone, like
    ``scipy.ndimage.convolve1d`` with mode="constant" twice, which the tests compare it with:
    importing scipy.ndimage cost every planned command ~0.12 s, measured before and after.)"""
    kernel = np.asarray(kernel, dtype=np.float64)
    r = len(kernel) // 2
    for axis in (0, 1):
        size = a.shape[axis]
        pad = [(0, 0)] * a.ndim
        pad[axis] = (r, r)
        padded = np.pad(a, pad)
        out = np.zeros(a.shape, dtype=np.result_type(a, kernel))
        window = [slice(None)] * a.ndim
        for i, k in enumerate(kernel[::-1]):
            window[axis] = slice(i, i + size)
            out += k * padded[tuple(window)]
        a = out
    return a


def window_mean(v: np.ndarray, half: int = NEIGHBOURHOOD) -> np.ndarray:
    """Mean of an (H, W) map over the (2·half + 1)² window, edges averaging what exists."""
    box = np.ones(2 * half + 1)
    return separable_filter(box, v) / separable_filter(box, np.ones_like(v))


class Wavefront:
    """Traces given per-pixel sample counts of one scene; accumulates filter sums and moments."""

    def __init__(self, scene, integrator=None, sensor: int = 0, path: str | Path = "the scene"):
        if not dr.is_jit_v(mi.Float):
            raise PhonglabError(f"adaptive sampling needs a JIT variant (llvm_* or cuda_*), "
                                f"not {mi.variant()}; pass e.g. --variant llvm_ad_rgb")
        self.scene = scene
        self.sensor = preflight(scene, path, sensor)
        self.integrator = integrator or scene.integrator()
        if not isinstance(self.integrator, mi.SamplingIntegrator):
            raise PhonglabError(f"{path}: its {self.integrator.class_name()} integrator is not "
                                f"sampled per pixel (a particle tracer splats light paths onto "
                                f"the film), so adaptive sampling cannot steer it; render it "
                                f"with a fixed --spp instead")
        names = film_channels(self.sensor, self.integrator, path)
        expected = ["Y"] if mi.is_monochromatic else ["R", "G", "B"]
        if names != expected:
            raise PhonglabError(f"{path}: adaptive sampling writes {', '.join(expected)} but the "
                                f"film's pixel_format gives {', '.join(names)}; set the film's "
                                f"pixel_format to {'luminance' if mi.is_monochromatic else 'rgb'}"
                                f" or render with a fixed --spp")
        film = self.sensor.film()
        self.width, self.height = (int(v) for v in film.crop_size())
        self.rfilter = film.rfilter()
        self.channels = 1 if mi.is_monochromatic else 3
        self.a, self.b = filter_integrals(self.rfilter)
        self.A, self.B = np.outer(self.a, self.a), np.outer(self.b, self.b)
        radius = self.A.shape[0] // 2
        #: offsets d = p − q (target pixel p, the sample's pixel q) the filter reaches
        self.offsets = [(iy - radius, ix - radius) for iy in range(self.A.shape[0])
                        for ix in range(self.A.shape[1]) if self.A[iy, ix] > 0]
        npix = self.width * self.height
        require_memory(HOST_BYTES_PER_PIXEL_OFFSET * len(self.offsets) * npix,
                       f"{path}: adaptive sampling of a {self.width} x {self.height} film",
                       "lower the resolution", why=" for its per-pixel sums")
        self.n = np.zeros(npix, dtype=np.int64)
        self.s1 = np.zeros((npix, self.channels))
        self.s2 = np.zeros((npix, self.channels))
        #: T[q, k] = Σ_{s in q} w(x_s − centre of q + d_k) · (f_s, 1), on the device (float32;
        #: only the developed image comes back to the host each pass)
        self.splat = dr.zeros(mi.Float, npix * len(self.offsets) * (self.channels + 1))
        self.sampler = mi.load_dict({"type": "independent"})

    @property
    def pixels(self) -> int:
        return self.width * self.height

    def trace(self, counts: np.ndarray, seed: int) -> int:
        """Trace ``counts[p]`` new samples in pixel p (flat index); returns the samples traced."""
        counts = np.asarray(counts, dtype=np.int64)
        total = int(counts.sum())
        if total == 0:
            return 0
        index = np.repeat(np.arange(self.pixels, dtype=np.uint32), counts)
        for k, start in enumerate(range(0, total, MAX_WAVEFRONT)):
            self._launch(index[start:start + MAX_WAVEFRONT], pass_seed(seed, k))
        return total

    def _camera_rays(self, idx):
        """Rays through a uniform point of each sample's pixel, as Mitsuba's film render makes
        them (integrator.cpp, render_sample); returns (ray, weight, position in the pixel)."""
        sampler, sensor = self.sampler, self.sensor
        x = idx % self.width
        pos = mi.Vector2f(mi.Float(x), mi.Float((idx - x) // self.width))
        wavelength = sampler.next_1d() if mi.is_spectral else mi.Float(0.5)
        time_ = dr.opaque(mi.Float, sensor.shutter_open())
        if sensor.shutter_open_time() > 0:
            time_ += sampler.next_1d() * sensor.shutter_open_time()
        u = sampler.next_2d()
        aperture = sampler.next_2d() if sensor.needs_aperture_sample() else mi.Point2f(0.5)
        scale = mi.ScalarVector2f(1.0 / self.width, 1.0 / self.height)
        ray, weight = sensor.sample_ray_differential(time_, wavelength, (pos + u) * scale,
                                                     aperture)
        return ray, weight, u

    def _launch(self, index: np.ndarray, seed: int) -> None:
        self.sampler.seed(dr.opaque(mi.UInt32, seed), len(index))
        idx = mi.UInt32(index)
        ray, weight, u = self._camera_rays(idx)
        spec, _, _ = self.integrator.sample(self.scene, self.sampler, ray,
                                            self.sensor.get_medium(), mi.Bool(True))
        spec = mi.unpolarized_spectrum(weight * spec)
        color = mi.spectrum_to_srgb(spec, ray.wavelengths, mi.Bool(True)) if mi.is_spectral \
            else spec
        values = [color[c] for c in range(self.channels)]
        s1 = [dr.zeros(mi.Float, self.pixels) for _ in values]
        s2 = [dr.zeros(mi.Float, self.pixels) for _ in values]
        for c, v in enumerate(values):
            dr.scatter_reduce(dr.ReduceOp.Add, s1[c], v, idx)
            dr.scatter_reduce(dr.ReduceOp.Add, s2[c], v * v, idx)
        width = len(self.offsets) * (self.channels + 1)
        for k, (dy, dx) in enumerate(self.offsets):
            # weight of target pixel q + d: filter at (sample position − target centre)
            w = (self.rfilter.eval(u.x - (dx + 0.5)) * self.rfilter.eval(u.y - (dy + 0.5)))
            base = idx * width + k * (self.channels + 1)
            for c, v in enumerate(values + [mi.Float(1.0)]):
                dr.scatter_reduce(dr.ReduceOp.Add, self.splat, w * v, base + c)
        dr.eval(s1, s2, self.splat)
        self.s1 += np.stack([np.array(a, dtype=np.float64) for a in s1], axis=1)
        self.s2 += np.stack([np.array(a, dtype=np.float64) for a in s2], axis=1)
        self.n += np.bincount(index, minlength=self.pixels)

    def image(self) -> np.ndarray:
        """(H, W, C): x_p = Σ_q T_qp / N_q ÷ Σ_q W_qp / N_q (module docstring), on the device."""
        inv = mi.Float(np.where(self.n > 0, 1.0 / np.maximum(self.n, 1), 0.0))
        p = dr.arange(mi.UInt32, self.pixels)
        px, py = mi.Int32(p % self.width), mi.Int32(p // self.width)
        width = len(self.offsets) * (self.channels + 1)
        total = [dr.zeros(mi.Float, self.pixels) for _ in range(self.channels + 1)]
        for k, (dy, dx) in enumerate(self.offsets):   # source q = target p − d
            qx, qy = px - dx, py - dy
            ok = (qx >= 0) & (qx < self.width) & (qy >= 0) & (qy < self.height)
            q = mi.UInt32(dr.select(ok, qy * self.width + qx, 0))
            scale = dr.gather(mi.Float, inv, q, ok)
            base = q * width + k * (self.channels + 1)
            for c in range(self.channels + 1):
                total[c] += dr.gather(mi.Float, self.splat, base + c, ok) * scale
        dr.eval(total)
        t = np.stack([np.array(a, dtype=np.float64) for a in total], axis=1)
        t = t.reshape(self.height, self.width, self.channels + 1)
        weight = t[..., -1:]
        return np.where(weight > 0, t[..., :-1] / np.where(weight > 0, weight, 1), 0.0)

    def variance(self, image: np.ndarray) -> np.ndarray:
        """(H, W, C) the delta-method variance of each filtered pixel (module docstring).

        The sum over source pixels q = p − d of ``[B_d (S2 − 2x S1 + x² N) − A_d² (S1 −
        x N)²/N] / (N (N − 1))`` expands into convolutions of per-pixel arrays with the
        fixed separable kernels B and A² (x = x_p factors out), :func:`separable_filter`.
        """
        h, w, c = self.height, self.width, self.channels
        n = self.n.reshape(h, w, 1).astype(np.float64)
        s1, s2 = self.s1.reshape(h, w, c), self.s2.reshape(h, w, c)
        scale = np.where(n > 1, 1.0 / np.maximum(n * (n - 1.0), 1.0), 0.0)

        a2 = self.a * self.a
        x = image
        # one filter call per kernel, on the arrays it filters stacked along the channels
        b_s2, b_s1, b_n = np.split(separable_filter(
            self.b, np.concatenate([s2 * scale, s1 * scale, n * scale], axis=2)), [c, 2 * c],
            axis=2)
        a_s11, a_s1, a_n = np.split(separable_filter(
            a2, np.concatenate([s1 * s1 * scale / np.maximum(n, 1.0), s1 * scale, n * scale],
                               axis=2)), [c, 2 * c], axis=2)
        num = (b_s2 - 2 * x * b_s1 + x * x * b_n - a_s11 + 2 * x * a_s1 - x * x * a_n)
        den, lonely = np.split(separable_filter(
            self.a, np.concatenate([(n > 0), (n == 1)], axis=2).astype(np.float64)), 2, axis=2)
        lonely = lonely > 0   # a source of 1 sample: unknown
        var = np.maximum(num, 0.0) / np.maximum(den * den, 1e-300)
        return np.where((den > 0) & ~lonely, var, np.inf)


def relative_error_map(image: np.ndarray, variance: np.ndarray) -> np.ndarray:
    """(H, W) e_p² = mean over channels of Var / (x² + ε)."""
    return np.mean(variance / (image * image + REL_EPS), axis=2)


def oracle_speedup(variance: np.ndarray, reference: np.ndarray, eps: float = REL_EPS) -> float:
    """The most any per-pixel allocation of samples can gain over uniform sampling, at equal
    total samples, on phonglab's relative MSE (issue 28: the limit adaptive sampling is
    measured against).

    ``variance``: (H, W, C) per-sample variance σ²_pc of each pixel value (a converged map:
    stderr² · spp of a high-spp render); ``reference``: (H, W, C) the converged image r.  With
    v_p = mean_c σ²_pc / (r_pc² + ε) and n_p samples in pixel p, the relMSE is mean_p v_p/n_p;
    at the same mean n̄, uniform gives mean(v)/n̄ and the Neyman allocation n_p ∝ √v_p (the
    module docstring's N_p*) gives mean(√v)²/n̄, so the speed-up is mean(v) / mean(√v)² ≥ 1
    (Cauchy–Schwarz; 1 exactly when every pixel has the same v).
    """
    v = np.mean(np.asarray(variance, np.float64)
                / (np.asarray(reference, np.float64) ** 2 + eps), axis=2)
    if not np.isfinite(v).all() or v.size == 0:
        raise PhonglabError("the oracle needs a finite variance map of at least one pixel; "
                            "render the map with more samples per pixel")
    root = float(np.mean(np.sqrt(v)))
    return float(np.mean(v)) / (root * root) if root > 0 else 1.0


def _check(target_error, max_seconds, max_spp, min_spp) -> None:
    """Refuse a target or cap no render can use (one sentence each)."""
    if not (isinstance(target_error, (int, float)) and math.isfinite(target_error)
            and 0 < target_error < 10):
        raise PhonglabError(f"the target error must be a relative RMSE in (0, 10), e.g. 0.02 "
                            f"for 2 %, got {target_error!r}")
    if max_seconds is not None:
        check_max_seconds(max_seconds)
    if not (isinstance(min_spp, int) and 2 <= min_spp <= MAX_SPP):
        raise PhonglabError(f"the pilot needs 2 to {MAX_SPP} samples per pixel (it estimates a "
                            f"variance), got {min_spp!r}")
    if max_spp is not None and not (isinstance(max_spp, int) and min_spp <= max_spp <= MAX_SPP):
        raise PhonglabError(f"--max-spp must be a whole number from the pilot's {min_spp} to "
                            f"{MAX_SPP}, got {max_spp!r}")


def allocation(err2: np.ndarray, n: np.ndarray, target_error: float,
               neighbourhood: bool = True) -> np.ndarray:
    """N_p* = √g_p · mean(v/√g) / E², v_p = e_p² N_p, g = v or, with the neighbourhood guard,
    g_p = max(v_p, mean of v over the window).

    g shapes the allocation (a pixel whose own samples show no variance yet gets its
    neighbours'), and the estimates v set its size: the predicted error mean(v/N*) is then E²
    exactly.  (Sizing it by g, N* = √g · mean √g / E², predicts E² only for g's own pixels
    and overshot: cornell_phong 128² stopped at 0.87 E with 36 % more samples than needed,
    textured_room at 0.78 E with 30 % more.)  Without the guard it is the Neyman allocation
    √v · mean √v / E² (module docstring)."""
    v = err2 * n
    v = np.where(np.isfinite(v), v, np.nanmax(np.where(np.isfinite(v), v, 0.0)))
    g = np.maximum(v, window_mean(v)) if neighbourhood else v
    root = np.sqrt(g)
    scale = float(np.mean(np.where(root > 0, v / np.where(root > 0, root, 1.0), 0.0)))
    return root * scale / (target_error * target_error)


def fit_time(counts: np.ndarray, seconds_left: float, seconds_per_sample: float) -> np.ndarray:
    """``counts`` scaled down so that the pass fits ``seconds_left`` at the last pass's
    measured cost per sample (all zero when no time is left): ``--max-seconds`` is honoured
    within one pass, which a pass of GROWTH times the samples would overrun."""
    if seconds_left <= 0:
        return np.zeros_like(counts)
    need = float(counts.sum()) * seconds_per_sample
    if need <= seconds_left:
        return counts
    return np.floor(counts * (seconds_left / need)).astype(counts.dtype)


def render_adaptive(scene, target_error: float, *, seed: int = 0, max_seconds: float | None = None,
                    max_spp: int | None = None, min_spp: int = MIN_SPP, integrator=None,
                    sensor: int = 0, neighbourhood: bool = True,
                    path: str | Path = "the scene") -> AdaptiveResult:
    """Render ``scene`` until its estimated relative RMSE is at most ``target_error``.

    The pilot gives every pixel ``min_spp`` samples; each further pass traces only the
    pixels below their allocation N_p* (module docstring), until the estimated error meets
    the target, no pixel needs more, a pixel would pass ``max_spp`` (those stop there), or
    ``max_seconds`` of wall time have passed (each pass after the pilot is sized to fit the
    time left at the measured cost per sample: :func:`fit_time`).
    """
    _check(target_error, max_seconds, max_spp, min_spp)
    cap = max_spp or MAX_SPP
    wf = Wavefront(scene, integrator, sensor, path)
    shape = (wf.height, wf.width)
    t0 = time.perf_counter()
    passes = []
    counts = np.full(wf.pixels, min_spp, dtype=np.int64)
    stopped, k = "target", 0
    while True:
        t = time.perf_counter()
        traced = wf.trace(counts, pass_seed(seed, k))
        image = wf.image()
        var = wf.variance(image)
        err2 = relative_error_map(image, var)
        estimate = math.sqrt(float(np.mean(np.where(np.isfinite(err2), err2, 0.0))))
        passes.append({"pixels": int(np.count_nonzero(counts)), "samples": traced,
                       "seconds": time.perf_counter() - t, "estimated_error": estimate})
        k += 1
        if estimate <= target_error and np.all(np.isfinite(err2)):
            break
        # In floating point up to the cap + 1 before the cast: an unreachable target asks for
        # more samples than int64 holds ("invalid value encountered in cast").
        want = np.ceil(np.minimum(allocation(err2, wf.n.reshape(shape), target_error,
                                             neighbourhood), cap + 1.0)).astype(np.int64).ravel()
        # At least a quarter more samples per pass: re-estimates creep, launches cost.
        step = np.maximum(want - wf.n, -(-wf.n // 4))
        counts = np.where(want > wf.n, np.minimum(step, (GROWTH - 1) * wf.n), 0)
        counts = np.clip(counts, 0, cap - wf.n)
        if not counts.any():
            stopped = "max_spp" if np.any(want > wf.n) else "target"
            break
        if max_seconds is not None:
            counts = fit_time(counts, max_seconds - (time.perf_counter() - t0),
                              passes[-1]["seconds"] / max(traced, 1))
            if not counts.any():
                stopped = "max_seconds"
                break
    seconds = time.perf_counter() - t0
    stderr = np.sqrt(np.nan_to_num(var, posinf=0.0))
    return AdaptiveResult(image.astype(np.float32), stderr.astype(np.float32),
                          wf.n.reshape(shape), seconds, float(target_error), estimate, stopped,
                          passes)


@dataclass
class AdaptiveSampling:
    """Adaptive sampling for :func:`phonglab.engine.render.render_scene_file`: :func:`render_adaptive`
    to ``target_error`` (its arguments), the spp map written beside the image set
    (:func:`spp_paths`)."""

    target_error: float
    max_seconds: float | None = None
    max_spp: int | None = None
    min_spp: int = MIN_SPP
    #: Mitsuba's warnings are silenced while the scene loads
    quiet_load = True

    def variant(self, variant: str | None) -> str:
        """The variant to load in: the one given, else the default JIT one (the active variant
        may be a scalar one, which this renderer refuses: choose, as a render does)."""
        return variant or default_variant()

    def settings(self) -> dict[str, Any]:
        """The ``<default>`` entries this sampling sets (none: it chooses the spp itself)."""
        return {}

    def check(self) -> None:
        _check(self.target_error, self.max_seconds, self.max_spp, self.min_spp)

    def render(self, sf, seed: int) -> tuple[AdaptiveResult, dict[str, Any]]:
        """The render and its header fields (target, estimate, stop, spp, passes, seed,
        integrator, depth, filter)."""
        result = render_adaptive(sf.scene, self.target_error, seed=seed,
                                 max_seconds=self.max_seconds, max_spp=self.max_spp,
                                 min_spp=self.min_spp, integrator=sf.integrator, path=sf.path)
        integ = sf.integrator or sf.scene.integrator()
        return result, {
            "adaptive": True, "target_error": self.target_error,
            "estimated_error": round(result.estimated_error, 6), "stopped": result.stopped,
            "spp_mean": round(result.total_spp, 3), "spp_min": int(result.spp.min()),
            "spp_max": int(result.spp.max()), "min_spp": self.min_spp,
            "passes": len(result.passes), "seed": seed, "integrator": integ.class_name(),
            "max_depth": sf.max_depth if sf.max_depth is not None
            else sf.declared.get("max_depth"),
            "filter": "the film's, density-normalised (phonglab.engine.adaptive)"}

    def extra_files(self, out: Path, result: AdaptiveResult):
        """The spp map, members of the render's file set: ``x.spp.exr`` (channel Y, the
        image's header) and ``x.spp.png``."""
        spp_exr, spp_img = spp_paths(out)
        spp = result.spp
        return [(spp_exr, ".tmp", lambda tmp, meta: exr.write_file(tmp, spp.astype(np.float32),
                                                                     meta)),
                (spp_img, ".png", lambda tmp, meta: spp_map_image(spp).save(tmp, format="PNG"))]


def render_file_adaptive(scene: str | Path, out: str | Path, target_error: float, *,
                         variant: str | None = None, seed: int = 0,
                         max_seconds: float | None = None, max_spp: int | None = None,
                         max_depth: int | None = None, min_spp: int = MIN_SPP,
                         params: dict[str, Any] | None = None, integrator=None,
                         extra_metadata: dict[str, Any] | None = None) -> AdaptiveResult:
    """Load ``scene``, render it adaptively and write ``out`` (+ .stderr.exr, .png, .spp.exr, .spp.png).

    :class:`AdaptiveSampling` through :func:`phonglab.engine.render.render_scene_file`, the one
    render of a scene file.  Everything is checked before the render: the arguments (one
    sentence each, first), the five output files, the scene.  ``max_depth`` applies as in
    :func:`phonglab.engine.render.render_file` (the scene's ``$max_depth`` default, else its
    integrator rebuilt with it); ``integrator`` (a ``mi.load_dict`` dictionary) replaces the
    scene's (the planner's models).  ``target_error`` is a noise target: see
    :mod:`phonglab.engine.metrics` for what it means against a converged reference.
    """
    sampling = AdaptiveSampling(target_error, max_seconds, max_spp, min_spp)
    sampling.check()
    return render_scene_file(scene, out, sampling, variant=variant, seed=seed,
                             max_depth=max_depth, params=params, integrator=integrator,
                             extra_metadata=extra_metadata)
