r"""Adaptive sampling: passes that trace rays only for the pixels whose error exceeds its budget.

Mitsuba's ``mi.render`` renders the whole film with one sample count.  :func:`render_adaptive`
runs its own Dr.Jit wavefront instead (:mod:`phonglab.engine.wavefront`: per pass, a given
number of new samples in each pixel, pixels with none costing nothing, and each pixel's
variance estimated from its samples: the source pixels' u_q, the relative variance one
sample of pixel q adds to the image's mean e²).  This module decides how many samples
each pixel gets and when to stop.

**Target and allocation.**  The target E is the image's relative RMSE against a converged
reference, √mean_pc((x − r)²/(r² + ε)) (:func:`phonglab.engine.metrics.relative_rmse`), as far as
noise makes it: the renderer has no depth-bias estimate, so E is the total error only for an
unbiased render (:mod:`phonglab.engine.metrics`, the one definition of E; the planner passes
√(E² − b²)).  Its square is the mean of the ``e_p²``, i.e. mean_q u_q/N_q.  Minimising the
samples Σ N_q subject to mean_q u_q/N_q = E² (Lagrange) gives the Neyman allocation
``N_q* = √u_q · mean √u / E²``.  **By time** (``by_time``): a sample of pixel q costs c_q
(:mod:`phonglab.engine.cost`, the pilot's cost map), and minimising the time Σ c_q N_q at the
same error gives ``N_q* = √(u_q/c_q) · mean(u √(c/u)) / E²``.  **The limit** each can reach
over uniform sampling at equal samples is mean(u)/mean(√u)², at equal time
mean(u)·mean(c)/mean(√(u c))² (uniform's time is N̄ Σ c, its error mean(u)/N̄; Cauchy–Schwarz;
:func:`neyman_gain`).  A pass adds ``min(N_q* − N_q, (GROWTH − 1)·N_q)`` samples to each
pixel below N_q* (re-estimated every pass, so a noisy pilot estimate cannot overshoot far);
the render stops when the estimated image error √mean e_p² <= E (1 + :data:`STOP_SLACK`),
when no pixel is below N_q*, or at a cap.

**Guards against pixels that only look converged** (no sample has found the light yet):
every pixel gets the pilot's :data:`MIN_SPP` samples, and the allocation is shaped by
``g_q = max(u_q, mean of u over the window)`` (:data:`NEIGHBOURHOOD`), so a pixel whose
own samples show no variance inherits its neighbours', while its size is set by the
estimates u themselves: ``N_q* = √g_q · mean(u/√g) / E²`` predicts exactly E²
(:func:`allocation`).
(The window's *max* would inflate a uniform-variance image's budget by the noise of nine
estimates; the mean is unbiased there.)
The bench (:mod:`phonglab.bench.adaptive_sweeps`) measures what they do: the fraction of
pixels whose true error exceeds three times their budget against a converged reference, with
and without the neighbourhood rule.

Sources: Rousselle, Knaus & Zwicker 2011 (relative MSE, adaptive sampling); the optimal
allocation N ∝ σ is the Neyman allocation of stratified sampling (Cochran, *Sampling
Techniques*, 3rd ed., §5.5).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from . import exr
from ..errors import PhonglabError
from .metrics import REL_EPS, check_target
from .outputs import spp_paths
from .render import MAX_SPP, pass_seed, render_scene_file
from .wavefront import Wavefront, relative_error_map, window_mean
from ..runtime import default_variant
from ..settings import check_max_seconds
from .spp_map import spp_map_image

#: Samples every pixel gets in the pilot pass (the first guard).
MIN_SPP = 16
#: Half-width of the window of the neighbourhood guard (2: 5×5).
NEIGHBOURHOOD = 2
#: A pass at most multiplies a pixel's sample count by this.
GROWTH = 4
#: No pass is started for an estimate within this fraction above E: the pass that sizing
#: aims at E lands on either side of it, and another pass for a 1 % miss costs a pass's
#: fixed work for nothing measurable (the estimate's own noise is larger).
STOP_SLACK = 0.01
#: Pass number whose seed the cost map's probe paths use (no pass reaches it).
COST_SEED = 1 << 20


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
    #: (H, W) u_q: relative variance one sample of source pixel q adds (× pixels) to mean e²
    source_variance: np.ndarray | None = None
    #: (H, W) c_q, the cost of one sample of pixel q in rays (by_time renders of ``path``)
    cost: np.ndarray | None = None
    #: per pass: pixels, samples, seconds (its tracing: trace_seconds), estimated_error
    passes: list[dict[str, Any]] = field(default_factory=list)
    metadata: dict[str, Any] = field(default_factory=dict)

    @property
    def total_spp(self) -> float:
        """Mean samples per pixel."""
        return float(self.spp.mean())

    def describe(self, scene: str | Path) -> str:
        """What the render of ``scene`` did, as ``phonglab render --adaptive`` prints it: its
        passes, samples and time, the estimated error against the target, why it stopped."""
        meta = self.metadata
        why = {"target": "the estimated error meets the target",
               "max_spp": "pixels reached --max-spp", "max_seconds": "--stop-after ran out"}
        return (f"rendered {scene} adaptively in {meta['variant']}: {len(self.passes)} passes, "
                f"{self.total_spp:.1f} spp on average ({meta['spp_min']} to {meta['spp_max']}), "
                f"{self.seconds:.3g} s; estimated relative RMSE {self.estimated_error:.4g} "
                f"(target {self.target_error:g}); stopped: {why[self.stopped]}")


def neyman_gain(u: np.ndarray, cost: np.ndarray | None = None) -> float:
    """The most a per-pixel allocation can gain over uniform sampling on the relative MSE
    Σ_q u_q/N_q: at equal samples mean(u)/mean(√u)², at equal time (one sample of pixel q
    costing c_q) mean(u)·mean(c)/mean(√(u c))² (module docstring, "The limit"); >= 1."""
    u = np.asarray(u, np.float64)
    c = np.ones_like(u) if cost is None else np.broadcast_to(np.asarray(cost, np.float64),
                                                              u.shape)
    if u.size == 0 or not (np.isfinite(u).all() and np.isfinite(c).all() and (c > 0).all()):
        raise PhonglabError("the oracle needs a finite variance map of at least one pixel "
                            "(and positive finite costs); render the map with more samples "
                            "per pixel")
    root = float(np.mean(np.sqrt(u * c)))
    return float(np.mean(u) * np.mean(c)) / (root * root) if root > 0 else 1.0


def oracle_speedup(variance: np.ndarray, reference: np.ndarray, eps: float = REL_EPS) -> float:
    """The most any per-pixel allocation of samples can gain over uniform sampling, at equal
    total samples, on phonglab's relative MSE (the limit adaptive sampling is measured
    against).

    ``variance``: (H, W, C) per-sample variance σ²_pc of each pixel value (a converged map:
    stderr² · spp of a high-spp render); ``reference``: (H, W, C) the converged image r.  With
    v_p = mean_c σ²_pc / (r_pc² + ε) and n_p samples in pixel p, the relMSE is mean_p v_p/n_p;
    at the same mean n̄, uniform gives mean(v)/n̄ and the Neyman allocation n_p ∝ √v_p (the
    module docstring's N_p*) gives mean(√v)²/n̄, so the speed-up is mean(v) / mean(√v)² ≥ 1
    (Cauchy–Schwarz; 1 exactly when every pixel has the same v).
    """
    return neyman_gain(np.mean(np.asarray(variance, np.float64)
                               / (np.asarray(reference, np.float64) ** 2 + eps), axis=2))


def _check(target_error, max_seconds, max_spp, min_spp) -> None:
    """Refuse a target or cap no render can use (one sentence each, naming the flag of
    ``phonglab render --adaptive``)."""
    check_target(target_error, "the target noise")
    if max_seconds is not None:
        check_max_seconds(max_seconds, "--stop-after")
    if not (isinstance(min_spp, int) and 2 <= min_spp <= MAX_SPP):
        raise PhonglabError(f"the pilot needs 2 to {MAX_SPP} samples per pixel (it estimates a "
                            f"variance), got {min_spp!r}")
    if max_spp is not None and not (isinstance(max_spp, int) and min_spp <= max_spp <= MAX_SPP):
        raise PhonglabError(f"--max-spp must be a whole number from the pilot's {min_spp} to "
                            f"{MAX_SPP}, got {max_spp!r}")


def allocation(u: np.ndarray, target_error: float, neighbourhood: bool = True,
               cost: np.ndarray | None = None) -> np.ndarray:
    """N_q* = √(g_q/c_q) · mean(u √(c/g)) / E², u_q the relative variance one sample of source
    pixel q adds (module docstring), c_q what it costs (1 without a cost map), g = u or, with
    the neighbourhood guard, g_q = max(u_q, mean of u over the window).

    g shapes the allocation (a pixel whose own samples show no variance yet gets its
    neighbours'), and the estimates u set its size: the predicted error mean(u/N*) is then E²
    exactly.  (Sizing it by g, N* = √g · mean √g / E², predicts E² only for g's own pixels
    and overshoots.)  Without the guard and costs it is the Neyman allocation
    √u · mean √u / E²; with costs, the one that minimises the time Σ c N at that error."""
    v = np.where(np.isfinite(u), u, np.nanmax(np.where(np.isfinite(u), u, 0.0)))
    g = np.maximum(v, window_mean(v, NEIGHBOURHOOD)) if neighbourhood else v
    if cost is not None:
        g = g / cost
    root = np.sqrt(g)
    scale = float(np.mean(np.where(root > 0, v / np.where(root > 0, root, 1.0), 0.0)))
    return root * scale / (target_error * target_error)


def fit_time(counts: np.ndarray, seconds_left: float, seconds_per_sample: float) -> np.ndarray:
    """``counts`` scaled down so that the pass fits ``seconds_left`` at the last pass's
    measured cost per sample (all zero when no time is left): ``--stop-after`` is honoured
    within one pass, which a pass of GROWTH times the samples would overrun."""
    if seconds_left <= 0:
        return np.zeros_like(counts)
    need = float(counts.sum()) * seconds_per_sample
    if need <= seconds_left:
        return counts
    return np.floor(counts * (seconds_left / need)).astype(counts.dtype)


def render_adaptive(scene, target_error: float, *, seed: int = 0, max_seconds: float | None = None,
                    max_spp: int | None = None, min_spp: int = MIN_SPP, integrator=None,
                    sensor: int = 0, neighbourhood: bool = True, by_time: bool = False,
                    path: str | Path = "the scene") -> AdaptiveResult:
    """Render ``scene`` until its estimated relative RMSE is at most ``target_error``.

    The pilot gives every pixel ``min_spp`` samples; each further pass traces only the
    pixels below their allocation N_p* (module docstring), until the estimated error meets
    the target, no pixel needs more, a pixel would pass ``max_spp`` (those stop there), or
    ``max_seconds`` of wall time have passed (each pass after the pilot is sized to fit the
    time left at the measured cost per sample: :func:`fit_time`).  ``by_time``: allocate for
    the least time instead of the fewest samples, with the pilot's cost map
    (:meth:`Wavefront.cost_map`; only for a ``path`` integrator, else by count), kept in
    :attr:`AdaptiveResult.cost`.  The arguments are checked once, by :class:`AdaptiveSampling`
    (one sentence each); the passes are :meth:`AdaptiveSampling.run`.
    """
    sampling = AdaptiveSampling(target_error, max_seconds, max_spp, min_spp, by_time)
    return sampling.run(scene, seed=seed, integrator=integrator, sensor=sensor,
                          neighbourhood=neighbourhood, path=path)


@dataclass
class AdaptiveSampling:
    """Adaptive sampling for :func:`phonglab.engine.render.render_scene_file`: :func:`render_adaptive`
    to ``target_error`` (its arguments, checked on construction), the spp map written beside
    the image set (:func:`spp_paths`)."""

    target_error: float
    max_seconds: float | None = None
    max_spp: int | None = None
    min_spp: int = MIN_SPP
    #: allocate by time (:func:`render_adaptive`'s ``by_time``)
    by_time: bool = False
    #: Mitsuba's warnings are silenced while the scene loads
    quiet_load = True

    def variant(self, variant: str | None) -> str:
        """The variant to load in: the one given, else the default JIT one (the active variant
        may be a scalar one, which this renderer refuses: choose, as a render does)."""
        return variant or default_variant()

    def settings(self) -> dict[str, Any]:
        """The ``<default>`` entries this sampling sets (none: it chooses the spp itself)."""
        return {}

    def __post_init__(self) -> None:
        """The target and caps are checked here, where they enter (one sentence each)."""
        _check(self.target_error, self.max_seconds, self.max_spp, self.min_spp)

    def render(self, sf, seed: int) -> tuple[AdaptiveResult, dict[str, Any]]:
        """The render and its header fields (target, estimate, stop, spp, passes, seed,
        integrator, depth, filter)."""
        result = self.run(sf.scene, seed=seed, integrator=sf.integrator, path=sf.path)
        integ = sf.integrator or sf.scene.integrator()
        return result, {
            "adaptive": True, "target_error": self.target_error,
            "estimated_error": round(result.estimated_error, 6), "stopped": result.stopped,
            "spp_mean": round(result.total_spp, 3), "spp_min": int(result.spp.min()),
            "spp_max": int(result.spp.max()), "min_spp": self.min_spp,
            "passes": len(result.passes), "seed": seed, "integrator": integ.class_name(),
            "by_time": result.cost is not None,
            "max_depth": sf.max_depth if sf.max_depth is not None
            else sf.declared.get("max_depth"),
            "filter": "the film's, density-normalised (phonglab.engine.adaptive)"}

    def run(self, scene, *, seed: int = 0, integrator=None, sensor: int = 0,
            neighbourhood: bool = True, path: str | Path = "the scene") -> AdaptiveResult:
        """The passes of :func:`render_adaptive` over a loaded ``scene`` (its other
        arguments), with this object's target and caps."""
        cap = self.max_spp or MAX_SPP
        wf = Wavefront(scene, integrator, sensor, path)
        shape = (wf.height, wf.width)
        t0 = time.perf_counter()
        passes = []
        counts = np.full(wf.pixels, self.min_spp, dtype=np.int64)
        stopped, k, costs = "target", 0, None
        wf.squares = True          # the pilot's samples all enter Q
        while True:
            t = time.perf_counter()
            traced = wf.trace(counts, pass_seed(seed, k))
            trace_seconds = time.perf_counter() - t
            image = wf.image()
            var, u = wf.estimate(image)
            err2 = relative_error_map(image, var)
            if k == 0:
                wf.select_exact(image, u)
                if self.by_time:
                    costs = wf.cost_map(pass_seed(seed, COST_SEED))
            estimate = math.sqrt(float(np.mean(np.where(np.isfinite(err2), err2, 0.0))))
            passes.append({"pixels": int(np.count_nonzero(counts)), "samples": traced,
                           "seconds": time.perf_counter() - t, "trace_seconds": trace_seconds,
                           "estimated_error": estimate})
            k += 1
            if (estimate <= self.target_error * (1.0 + STOP_SLACK)
                    and np.all(np.isfinite(err2))):
                break
            # In floating point up to the cap + 1 before the cast: an unreachable target asks for
            # more samples than int64 holds ("invalid value encountered in cast").
            want = np.ceil(np.minimum(allocation(u, self.target_error, neighbourhood, costs),
                                      cap + 1.0)).astype(np.int64).ravel()
            # At least a quarter more samples per pass: re-estimates creep, launches cost.
            step = np.maximum(want - wf.n, -(-wf.n // 4))
            counts = np.where(want > wf.n, np.minimum(step, (GROWTH - 1) * wf.n), 0)
            counts = np.clip(counts, 0, cap - wf.n)
            if not counts.any():
                stopped = "max_spp" if np.any(want > wf.n) else "target"
                break
            if self.max_seconds is not None:
                counts = fit_time(counts, self.max_seconds - (time.perf_counter() - t0),
                                  passes[-1]["seconds"] / max(traced, 1))
                if not counts.any():
                    stopped = "max_seconds"
                    break
        seconds = time.perf_counter() - t0
        stderr = np.sqrt(np.nan_to_num(var, posinf=0.0))
        return AdaptiveResult(image.astype(np.float32), stderr.astype(np.float32),
                              wf.n.reshape(shape), seconds, float(self.target_error), estimate,
                              stopped, u, costs, passes)

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
                         extra_metadata: dict[str, Any] | None = None,
                         by_time: bool = False) -> AdaptiveResult:
    """Load ``scene``, render it adaptively and write ``out`` (+ .stderr.exr, .png, .spp.exr, .spp.png).

    :class:`AdaptiveSampling` through :func:`phonglab.engine.render.render_scene_file`, the one
    render of a scene file.  Everything is checked before the render: the arguments (one
    sentence each, first), the five output files, the scene.  ``max_depth`` applies as in
    :func:`phonglab.engine.render.render_file` (the scene's ``$max_depth`` default, else its
    integrator rebuilt with it); ``integrator`` (a ``mi.load_dict`` dictionary) replaces the
    scene's (the planner's models).  ``target_error`` is a noise target: see
    :mod:`phonglab.engine.metrics` for what it means against a converged reference.
    """
    sampling = AdaptiveSampling(target_error, max_seconds, max_spp, min_spp, by_time)
    return render_scene_file(scene, out, sampling, variant=variant, seed=seed,
                             max_depth=max_depth, params=params, integrator=integrator,
                             extra_metadata=extra_metadata)
