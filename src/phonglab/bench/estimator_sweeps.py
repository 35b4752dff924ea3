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

Each sweep is a list of jobs (:class:`phonglab.parallel.Job`: one per estimator cell, per
cost round, per (light, p, θ_i) cell of the stability map) run by
:func:`phonglab.bench.jobs.run_jobs`, serially or on a Dask cluster; a job carries its seeds
and measures its own times, after the warm-up its worker process does once
(:func:`_warm_up`, :func:`_warm_stability`).
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

import numpy as np

from ..parallel import Job, Runner
from ..physics.estimators import METHODS, Estimate, Problem, ReflectionEstimators, exact_value
from .analysis import stability_verdict, stability_z_crit
from .config import (ESTIMATOR_SCENES, STABILITY_ANGLES, STABILITY_EXPONENTS, STABILITY_LIGHTS,
                     STABILITY_N, VARIANT, Config)
from .csvlog import open_log
from .jobs import run_jobs

#: The pure specular lobe of the stability map.
_SPECULAR = dict(bsdf="phong", diffuse_reflectance=0.0, specular_reflectance=1.0)


@functools.lru_cache(maxsize=None)
def _process_estimators(sweep: str) -> ReflectionEstimators:
    """The estimators of ``sweep`` ('estimators' or 'stability') in this process (jobs share it)."""
    first = next(iter(ESTIMATOR_SCENES.values())) if sweep == "estimators" else Problem(**_SPECULAR)
    return ReflectionEstimators(first)


@functools.lru_cache(maxsize=None)
def _exact(scene: str) -> float:
    return exact_value(ESTIMATOR_SCENES[scene])


@functools.lru_cache(maxsize=None)
def _warm_up(scene: str, method: str, n: int, repeats: int) -> tuple[Estimate, float]:
    """Once per process: the first call of ``method`` on ``scene`` (it traces and compiles, or
    loads from the kernel cache) and the steady time of ``n`` samples after it."""
    est = _process_estimators("estimators").set(ESTIMATOR_SCENES[scene])
    first = est.run(method, n, seed=99)
    steady = float(np.median([est.run(method, n, seed=98 - r).seconds for r in range(repeats)]))
    return first, steady


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


def estimator_jit_job(scene: str, method: str, cfg: Config) -> list[tuple[str, dict]]:
    """Job: the jit.csv row of ``method`` on ``scene`` (first call, steady time, compile stats)."""
    first, steady = _warm_up(scene, method, cfg.estimator_ns[0], cfg.repeats)
    return [("jit", dict(group="estimator", method=method, scene=scene, variant=VARIANT,
                         first_call_s=first.seconds, steady_s=steady, compile_ms=first.compile_ms,
                         kernels=first.kernels, cache_hits=first.cache_hits))]


def estimator_job(scene: str, method: str, n: int, k: int, cfg: Config) -> list[tuple[str, dict]]:
    """Job: the results.csv row of ``method`` on ``scene`` at ``n`` samples (the k-th N)."""
    first, _ = _warm_up(scene, method, cfg.estimator_ns[0], cfg.repeats)
    est = _process_estimators("estimators").set(ESTIMATOR_SCENES[scene])
    return [("results", _estimator_row(est, method, scene, n, k, _exact(scene), cfg, first.seconds))]


def cost_job(scene: str, r: int, methods: tuple[str, ...], cfg: Config) -> list[tuple[str, dict]]:
    """Job: cost round ``r`` on ``scene``, ``methods`` one after the other (after their warm-up)."""
    for method in methods:
        _warm_up(scene, method, cfg.estimator_ns[0], cfg.repeats)
    est = _process_estimators("estimators").set(ESTIMATOR_SCENES[scene])
    n = cfg.estimator_ns[-1]
    return [("cost", dict(scene=scene, method=method, round=r, samples=n,
                          seconds=est.run(method, n, seed=70_000 + r).seconds))
            for method in methods]


def sweep_estimators(out: Path, cfg: Config, runner: Runner) -> None:
    """Error and steady-state time of each estimator against N, on :data:`ESTIMATOR_SCENES`."""
    log, jit = open_log(out, "results"), open_log(out, "jit")
    jobs, order = [], {"results": [], "jit": []}
    for scene in ESTIMATOR_SCENES:
        for method in METHODS:
            key = dict(group="estimator", method=method, scene=scene, variant=VARIANT)
            order["jit"].append(key)
            if not jit.has(**key):
                jobs.append(Job(estimator_jit_job, (scene, method, cfg), key=("jit", scene, method)))
            for k, n in enumerate(cfg.estimator_ns):
                order["results"].append(dict(key, samples=n))
                if not log.has(**key, samples=n):
                    jobs.append(Job(estimator_job, (scene, method, n, k, cfg), key=(scene, method, n)))
    run_jobs(runner, out, jobs, order, "estimators")
    sweep_cost(out, cfg, runner)


def sweep_cost(out: Path, cfg: Config, runner: Runner) -> None:
    """Cost per estimate at the largest N, methods interleaved (rotated order each round).

    Load from other processes then falls on all methods alike; the median per method is
    what the efficiency (σ²·t) comparison uses.  One job per (problem, round).
    """
    cost = open_log(out, "cost")
    jobs, order = [], {"cost": []}
    for scene in ESTIMATOR_SCENES:
        for r in range(cfg.cost_rounds):
            rotated = METHODS[r % len(METHODS):] + METHODS[:r % len(METHODS)]
            order["cost"] += [dict(scene=scene, method=m, round=r) for m in rotated]
            todo = tuple(m for m in rotated if not cost.has(scene=scene, method=m, round=r))
            if todo:
                jobs.append(Job(cost_job, (scene, r, todo, cfg), key=("cost", scene, r)))
    run_jobs(runner, out, jobs, order, "cost")


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


@functools.lru_cache(maxsize=None)
def _warm_stability(seeds: int) -> ReflectionEstimators:
    """Once per process: compile every estimator for both lights before cells are timed, at the
    cells' own size (``mis_optimal``'s frozen function records per size, and on its first two
    calls of one: ``dr.freeze`` makes a literal that changed opaque and records again)."""
    est = _process_estimators("stability")
    for method in METHODS:
        for light in STABILITY_LIGHTS.values():
            for seed in (1, 2):
                est.set(Problem(**_SPECULAR, **light))
                est.run(method, STABILITY_N, seed=seed, batches=seeds)
    return est


def stability_job(cells: tuple[tuple[str, str, float, float, int], ...], seeds: int,
                  z_crit: float) -> list[tuple[str, dict]]:
    """Job: the stability.csv rows of ``cells`` ((light, method, p, θ_i, seed) each)."""
    est = _warm_stability(seeds)
    return [("stability", _stability_row(est, light, method, p, theta, seed, seeds, z_crit))
            for light, method, p, theta, seed in cells]


def sweep_stability(out: Path, cfg: Config, runner: Runner) -> None:
    """The stability map: each estimator × p × θ_i × light at N = :data:`STABILITY_N` samples.

    One job per (light, p, θ_i): its estimators one after the other, as the serial order has
    them (each cell ~5 ms, so a job of one cell would cost about as much in scheduling as in
    work; docs/cluster.md).
    """
    log = open_log(out, "stability")
    z_crit = stability_z_crit()
    # Methods innermost: the per-(light, method) median time that the MIS comparison uses
    # (analysis.mis_ratios) then sees the same load drift for every method.
    cells = [(lt, m, p, t) for lt in STABILITY_LIGHTS for p in STABILITY_EXPONENTS
             for t in STABILITY_ANGLES for m in METHODS]
    order = {"stability": [dict(light=lt, method=m, exponent=p, theta_i=t) for lt, m, p, t in cells]}
    rows: dict[tuple, list] = {}
    for i, (light, method, p, theta) in enumerate(cells):
        if not log.has(light=light, method=method, exponent=p, theta_i=theta):
            rows.setdefault((light, p, theta), []).append((light, method, p, theta, 20_000 + i))
    jobs = [Job(stability_job, (tuple(todo), cfg.stability_seeds, z_crit), key=("stability",) + k)
            for k, todo in rows.items()]
    run_jobs(runner, out, jobs, order, "stability")
