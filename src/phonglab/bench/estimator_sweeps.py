r"""Sweeps of the reflection-equation estimators: error and time against N, and the stability map.

* :func:`sweep_estimators` — the five estimators of :mod:`phonglab.physics.estimators` on
  :data:`~phonglab.bench.config.ESTIMATOR_SCENES`: for each N the RMSE against the exact
  value (quadrature) over S seeds, the pooled per-sample variance N·mean(stderr²) and the
  steady-state wall time of one N-sample estimate (median of repeats after a warm-up call,
  whose own time and JIT statistics go to ``jit.csv``); then :func:`sweep_cost`, the cost
  per estimate at the largest N with the methods interleaved.
* :func:`sweep_stability` — every estimator (``mis_optimal`` included) × exponent × θ_i × light
  of the stability grid (the estimators interleaved cell by cell),
  pure specular lobe (k_d = 0, k_s = 1), N = :data:`~phonglab.bench.config.STABILITY_N`;
  the verdict is :func:`phonglab.bench.analysis.stability_verdict`.  The bias z-score is
  mean error / (pooled standard error / √S); with a zero standard error it is 0 when the
  estimate is exact to 10⁻⁶ and ∞ otherwise (a silent failure).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .. import registration
from ..physics.estimators import METHODS, Problem, ReflectionEstimators, exact_value
from .analysis import stability_verdict, stability_z_crit
from .config import (ESTIMATOR_SCENES, STABILITY_ANGLES, STABILITY_EXPONENTS, STABILITY_LIGHTS,
                     STABILITY_N, VARIANT, Config)
from .csvlog import open_log, progress_bar


def _estimator_row(est: ReflectionEstimators, method: str, scene: str, n: int, k: int,
                   mu: float, cfg: Config, first_seconds: float) -> dict:
    """One results.csv row: steady time of an n-sample estimate and its error over the seeds."""
    seeds = cfg.estimator_seeds
    times = [est.run(method, n, seed=5000 + r).seconds for r in range(cfg.repeats)]
    e = est.run(method, n, seed=10_000 + k, batches=seeds)
    mse = float(np.mean((e.values - mu) ** 2))
    return dict(group="estimator", method=method, scene=scene, variant=VARIANT,
                samples=n, seeds=seeds, wall_time_s=float(np.median(times)),
                first_call_s=first_seconds, rmse=math.sqrt(mse), rel_mse=mse / mu ** 2,
                var_n=float(np.mean(e.stderr ** 2)) * n,
                nan_count=e.nan_count + e.inf_count, reference=mu)


def sweep_estimators(out: Path, cfg: Config, progress: bool = True) -> None:
    """Error and steady-state time of each estimator against N, on :data:`ESTIMATOR_SCENES`."""
    registration.register(VARIANT)
    log, jit = open_log(out, "results"), open_log(out, "jit")
    ns = cfg.estimator_ns
    est = ReflectionEstimators(next(iter(ESTIMATOR_SCENES.values())))
    bar = progress_bar(len(ESTIMATOR_SCENES) * len(METHODS) * len(ns), "estimators", progress)
    for scene, problem in ESTIMATOR_SCENES.items():
        est.set(problem)
        mu = exact_value(problem)
        for method in METHODS:
            # Warm-up: the first call traces and compiles (or loads from the kernel cache).
            first = est.run(method, ns[0], seed=99)
            steady_first = float(np.median([est.run(method, ns[0], seed=98 - r).seconds
                                             for r in range(cfg.repeats)]))
            if not jit.has(group="estimator", method=method, scene=scene, variant=VARIANT):
                jit.add(dict(group="estimator", method=method, scene=scene, variant=VARIANT,
                             first_call_s=first.seconds, steady_s=steady_first,
                             compile_ms=first.compile_ms, kernels=first.kernels,
                             cache_hits=first.cache_hits))
            for k, n in enumerate(ns):
                bar.update()
                if not log.has(group="estimator", method=method, scene=scene, variant=VARIANT,
                               samples=n):
                    log.add(_estimator_row(est, method, scene, n, k, mu, cfg, first.seconds))
    bar.close()
    sweep_cost(out, cfg, est)


def sweep_cost(out: Path, cfg: Config, est: ReflectionEstimators) -> None:
    """Cost per estimate at the largest N, methods interleaved (rotated order each round).

    Load from other processes then falls on all methods alike; the median per method is
    what the efficiency (σ²·t) comparison uses.
    """
    cost = open_log(out, "cost")
    n = cfg.estimator_ns[-1]
    for scene, problem in ESTIMATOR_SCENES.items():
        est.set(problem)
        for r in range(cfg.cost_rounds):
            order = METHODS[r % len(METHODS):] + METHODS[:r % len(METHODS)]
            for method in order:
                if not cost.has(scene=scene, method=method, round=r):
                    cost.add(dict(scene=scene, method=method, round=r, samples=n,
                                  seconds=est.run(method, n, seed=70_000 + r).seconds))


def _stability_row(est: ReflectionEstimators, light: str, method: str, p: float, theta: float,
                   seed: int, seeds: int, z_crit: float) -> dict:
    """One stability.csv row: the cell's error, bias z-score and verdict."""
    n = STABILITY_N
    problem = Problem(bsdf="phong", diffuse_reflectance=0.0, specular_reflectance=1.0,
                      **STABILITY_LIGHTS[light], exponent=p, theta_i=theta)
    est.set(problem)
    mu = exact_value(problem)
    e = est.run(method, n, seed=seed, batches=seeds)
    finite = np.isfinite(e.values)
    err = e.values - mu
    rel_rmse = float(math.sqrt(np.mean(err ** 2)) / mu) if finite.all() else float("nan")
    se_mean = math.sqrt(float(np.mean(e.stderr ** 2)) / seeds)
    mean_err = float(np.mean(err))
    if se_mean > 0:
        z = mean_err / se_mean
    else:
        z = 0.0 if abs(mean_err) <= 1e-6 * abs(mu) else float("inf")
    verdict, reason = stability_verdict(rel_rmse, mean_err / mu, z, e.nan_count + e.inf_count, z_crit)
    return dict(light=light, method=method, exponent=p, theta_i=theta, samples=n, seeds=seeds,
                exact=mu, mean=float(np.mean(e.values)), rel_rmse=rel_rmse,
                rel_stderr=float(np.sqrt(np.mean(e.stderr ** 2))) / mu,
                var_n=float(np.mean(e.stderr ** 2)) * n, bias_z=z,
                nan_count=e.nan_count, inf_count=e.inf_count, seconds=e.seconds / seeds,
                verdict=verdict, reason=reason)


def sweep_stability(out: Path, cfg: Config, progress: bool = True) -> None:
    """The stability map: each estimator × p × θ_i × light at N = :data:`STABILITY_N` samples."""
    registration.register(VARIANT)
    log = open_log(out, "stability")
    z_crit = stability_z_crit()
    base = dict(bsdf="phong", diffuse_reflectance=0.0, specular_reflectance=1.0)
    est = ReflectionEstimators(Problem(**base))
    for method in METHODS:            # warm-up: compile every estimator before timing cells
        for light in STABILITY_LIGHTS.values():
            est.set(Problem(**base, **light))
            est.run(method, STABILITY_N, seed=1)
    # Methods innermost: the per-(light, method) median time that the MIS comparison uses
    # (analysis.mis_ratios) then sees the same load drift for every method.
    cells = [(lt, m, p, t) for lt in STABILITY_LIGHTS for p in STABILITY_EXPONENTS
             for t in STABILITY_ANGLES for m in METHODS]
    bar = progress_bar(len(cells), "stability", progress)
    for i, (light, method, p, theta) in enumerate(cells):
        bar.update()
        if not log.has(light=light, method=method, exponent=p, theta_i=theta):
            log.add(_stability_row(est, light, method, p, theta, 20_000 + i, cfg.stability_seeds,
                                   z_crit))
    bar.close()
