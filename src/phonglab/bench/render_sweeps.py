r"""Sweeps of full renders: error against time per BSDF, variants, and render-time ratios.

* :func:`sweep_renders` — the Cornell box (:func:`phonglab.bench.cornell.render_setups`,
  32 px): RMSE against the cached high-sample reference (its own noise subtracted,
  :func:`phonglab.engine.metrics.errors`) and steady render time against spp, for ``lambert`` vs
  ``diffuse`` (every surface of that BSDF) and ``phong`` vs ``plastic`` vs ``roughplastic``
  boxes (walls ``diffuse``).
* :func:`sweep_variants` — ``llvm_ad_rgb`` against ``scalar_rgb`` on a 16 px box
  (``cuda_ad_rgb`` when Dr.Jit finds a CUDA device; skipped with a note otherwise).
* :func:`sweep_ratios` — render-time ratios lambert/diffuse, phong/plastic,
  phong/roughplastic on the same scene, spp and variant: A/B pairs in alternating order
  (ABBA), the median of the per-pair ratios (:func:`phonglab.bench.analysis.ratio_summary`).
* :func:`sweep_whitted_units` — ``whitted`` in graphics against radiance units on
  :data:`~phonglab.bench.config.WHITTED_SCENES` (their own settings, only ``units`` swapped):
  ABBA pairs of steady renders, and the JIT kernels each render launches.

Every render goes through :func:`phonglab.engine.render.render_scene` (one pass; its
``pass_seconds[0]`` is the timed wall time, image evaluated and copied).

Each sweep is a list of jobs run by :func:`phonglab.bench.jobs.run_jobs`, serially or on a
Dask cluster: one per (set-up, spp) cell of the renders (after the set-up's load and warm-up,
done once per worker process: :func:`_setup`), one per (variant, BSDF) of the variant
comparison, one per A/B pair of the ratios and of the whitted units (both renders of a pair
back to back in one process).
References are rendered first, their passes spread over the same runner.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

import drjit as dr
import mitsuba as mi
import numpy as np

from .. import registration
from ..engine.metrics import errors
from ..parallel import Job, Runner
from ..engine.references import Reference
from ..engine.render import render_scene
from ..engine.scenes import load_scene
from .config import (RATIO_COMPARISONS, RATIO_RES, VARIANT, VARIANT_RES, WHITTED_SCENES, WHITTED_SPP,
                     Config)
from .cornell import CornellSpec, ratio_spec, render_jit, render_setups, timed_render
from .csvlog import open_log
from .jobs import Rows, run_jobs


def measure_render(scene, spp: int, repeats: int, ref: Reference) -> dict:
    """Median wall time and mean errors of ``repeats`` renders at ``spp`` against ``ref``."""
    times, errs = [], []
    for r in range(repeats):
        result = render_scene(scene, spp, seed=100 * spp + r)
        times.append(result.pass_seconds[0])
        errs.append(errors(result.image, ref.image, ref.stderr))
    mse = float(np.mean([e["mse"] for e in errs]))
    return dict(samples=spp, seeds=repeats, wall_time_s=float(np.median(times)),
                rmse=math.sqrt(max(mse, 0.0)), rel_mse=float(np.mean([e["rel_mse"] for e in errs])),
                var_n="", nan_count=sum(e["nan_count"] for e in errs))


@functools.lru_cache(maxsize=8)
def _setup(spec: CornellSpec, repeats: int) -> tuple:
    """Once per process and set-up: (scene, first-call s, compile ms, kernels, cache hits, steady s)."""
    scene = spec.load(VARIANT)
    first, ms, kernels, hits = render_jit(scene, 1, seed=7)
    steady = float(np.median([timed_render(scene, 1, seed=8 + r) for r in range(repeats)]))
    return scene, first, ms, kernels, hits, steady


def render_jit_job(scene_name: str, method: str, spec: CornellSpec, repeats: int) -> Rows:
    """Job: the jit.csv row of a render set-up."""
    _, first, ms, kernels, hits, steady = _setup(spec, repeats)
    return [("jit", dict(group="render", method=method, scene=scene_name, variant=VARIANT,
                         first_call_s=first, steady_s=steady, compile_ms=ms, kernels=kernels,
                         cache_hits=hits))]


def render_job(scene_name: str, method: str, spec: CornellSpec, spp: int, repeats: int,
               ref: Reference, ref_label: str) -> Rows:
    """Job: the results.csv row of a render set-up at ``spp`` against ``ref``."""
    scene, first, *_ = _setup(spec, repeats)
    return [("results", dict(group="render", method=method, scene=scene_name, variant=VARIANT,
                             first_call_s=first, reference=ref_label,
                             **measure_render(scene, spp, repeats, ref)))]


def sweep_renders(out: Path, cfg: Config, runner: Runner, cache: Path | None = None) -> None:
    """RMSE against the reference and steady time against spp, per BSDF, on the Cornell box."""
    log, jit = open_log(out, "results"), open_log(out, "jit")
    jobs, order = [], {"results": [], "jit": []}
    for scene_name, methods in render_setups().items():
        for method, (spec, ref_spec) in methods.items():
            key = dict(group="render", method=method, scene=scene_name, variant=VARIANT)
            order["jit"].append(key)
            order["results"] += [dict(key, samples=spp) for spp in cfg.render_spps]
            todo = [spp for spp in cfg.render_spps if not log.has(**key, samples=spp)]
            if not jit.has(**key):
                jobs.append(Job(render_jit_job, (scene_name, method, spec, cfg.repeats),
                                key=("jit", scene_name, method)))
            if todo:
                ref = ref_spec.reference(cfg.reference_spp, VARIANT, cache, runner)
                label = f"{ref_spec.boxes} {cfg.reference_spp} spp"
                jobs += [Job(render_job, (scene_name, method, spec, spp, cfg.repeats, ref, label),
                             key=(scene_name, method, spp)) for spp in todo]
    run_jobs(runner, out, jobs, order, "renders")


def variant_job(variant: str, method: str, spps: tuple[int, ...], need_jit: bool, repeats: int,
                ref: Reference, ref_label: str) -> Rows:
    """Job: the 16 px box of ``method`` in ``variant``: its jit.csv row (when ``need_jit``) and
    its results.csv rows at ``spps``."""
    scene_name = f"cornell-{VARIANT_RES}px"
    rows: Rows = []
    try:
        registration.register(variant)
        scene = CornellSpec(walls=method, boxes=method, res=VARIANT_RES).load(variant)
        first = timed_render(scene, 1, seed=7)
        steady = float(np.median([timed_render(scene, 1, seed=8 + r) for r in range(repeats)]))
        if need_jit:
            rows.append(("jit", dict(group="variant", method=method, scene=scene_name,
                                     variant=variant, first_call_s=first, steady_s=steady)))
        for spp in spps:
            rows.append(("results", dict(group="variant", method=method, scene=scene_name,
                                         variant=variant, first_call_s=first, reference=ref_label,
                                         **measure_render(scene, spp, repeats, ref))))
    finally:
        registration.register(VARIANT)
    return rows


def sweep_variants(out: Path, cfg: Config, runner: Runner, cache: Path | None = None) -> list[str]:
    """llvm_ad_rgb against scalar_rgb (and cuda_ad_rgb with a GPU) on a 16 px Cornell box.

    Returns notes (e.g. why cuda_ad_rgb was skipped).  Whether CUDA is there is asked here,
    where the command runs; a cluster's workers are assumed to be alike.
    """
    notes = []
    variants = [VARIANT, "scalar_rgb"]
    if dr.has_backend(dr.JitBackend.CUDA):
        variants.append("cuda_ad_rgb")
    else:
        notes.append("cuda_ad_rgb skipped: Dr.Jit found no CUDA device on this machine.")
    log, jit = open_log(out, "results"), open_log(out, "jit")
    scene_name = f"cornell-{VARIANT_RES}px"
    ref = None
    label = f"diffuse {cfg.reference_spp} spp {VARIANT}"
    jobs, order = [], {"results": [], "jit": []}
    for variant in variants:
        for method in ("lambert", "diffuse"):
            key = dict(group="variant", method=method, scene=scene_name, variant=variant)
            order["jit"].append(key)
            order["results"] += [dict(key, samples=spp) for spp in cfg.variant_spps]
            todo = tuple(spp for spp in cfg.variant_spps if not log.has(**key, samples=spp))
            need_jit = not jit.has(**key)
            if todo or need_jit:
                ref = ref or CornellSpec(walls="diffuse", boxes="diffuse", res=VARIANT_RES).reference(
                    cfg.reference_spp, VARIANT, cache, runner)
                jobs.append(Job(variant_job, (variant, method, todo, need_jit, cfg.repeats, ref, label),
                                key=(variant, method)))
    run_jobs(runner, out, jobs, order, "variants")
    return notes


@functools.lru_cache(maxsize=4)
def _ratio_scenes(a: str, b: str, which: str, spp: int) -> dict:
    """Once per process and comparison: both scenes, loaded and warmed up (JIT excluded)."""
    scenes = {m: ratio_spec(m, which).load(VARIANT) for m in (a, b)}
    for m in (a, b):
        timed_render(scenes[m], spp, seed=1)
    return scenes


def ratio_job(name: str, a: str, b: str, which: str, pair: int, spp: int) -> Rows:
    """Job: one A/B pair of a render-time comparison, both renders back to back in one
    process (A first in even pairs, B first in odd ones: ABBA over the pairs)."""
    scenes = _ratio_scenes(a, b, which, spp)
    order = (a, b) if pair % 2 == 0 else (b, a)
    t = {m: timed_render(scenes[m], spp, seed=1000 + pair) for m in order}
    return [("ratios", dict(comparison=name, a=a, b=b, pair=pair,
                            scene=f"cornell {RATIO_RES}px {which}", variant=VARIANT,
                            spp=spp, t_a=t[a], t_b=t[b], ratio=t[a] / t[b]))]


def sweep_ratios(out: Path, cfg: Config, runner: Runner) -> None:
    """Alternating A/B render timings (ABBA order) for the render-time targets."""
    log = open_log(out, "ratios")
    jobs, order = [], {"ratios": []}
    for name, a, b, which in RATIO_COMPARISONS:
        for pair in range(cfg.ratio_pairs):
            order["ratios"].append(dict(comparison=name, pair=pair))
            if not log.has(comparison=name, pair=pair):
                jobs.append(Job(ratio_job, (name, a, b, which, pair, cfg.ratio_spp),
                                key=("ratios", name, pair)))
    run_jobs(runner, out, jobs, order, "ratios")


@functools.lru_cache(maxsize=2)
def _whitted_setup(name: str) -> tuple:
    """Once per process and scene: (scene, integrator per units, kernels per units), warmed up."""
    scene = load_scene(name, VARIANT)
    settings = scene.integrator().parameters()
    units = {u: mi.load_dict(dict(settings, units=u)) for u in ("graphics", "radiance")}
    kernels = {u: render_jit_integrator(scene, integrator)     # warm-up: tracing and JIT excluded
               for u, integrator in units.items()}
    return scene, units, kernels


def whitted_job(name: str, pair: int) -> Rows:
    """Job: one ABBA pair of ``whitted`` renders of ``name`` in graphics and radiance units,
    back to back in one process, and the kernels each render launches."""
    scene, units, kernels = _whitted_setup(name)
    order = ("graphics", "radiance") if pair % 2 == 0 else ("radiance", "graphics")
    t = {u: render_scene(scene, WHITTED_SPP, seed=1000 + pair,
                         integrator=units[u]).pass_seconds[0] for u in order}
    return [("whitted", dict(scene=name, pair=pair, spp=WHITTED_SPP, t_graphics=t["graphics"],
                             t_radiance=t["radiance"], ratio=t["graphics"] / t["radiance"],
                             kernels_graphics=kernels["graphics"],
                             kernels_radiance=kernels["radiance"]))]


def sweep_whitted_units(out: Path, cfg: Config, runner: Runner) -> None:
    """ABBA pairs of ``whitted`` renders in graphics and in radiance units, same scene and spp
    (the kernels compiled beforehand); each row also records the kernels each render launched.
    One job per pair."""
    log = open_log(out, "whitted")
    jobs, order = [], {"whitted": []}
    for name in WHITTED_SCENES:
        for pair in range(cfg.ratio_pairs):
            order["whitted"].append(dict(scene=name, pair=pair))
            if not log.has(scene=name, pair=pair):
                jobs.append(Job(whitted_job, (name, pair), key=("whitted", name, pair)))
    run_jobs(runner, out, jobs, order, "whitted units")


def render_jit_integrator(scene, integrator) -> int:
    """JIT kernels launched by one render of ``scene`` with ``integrator`` (after a warm-up)."""
    render_scene(scene, WHITTED_SPP, seed=1, integrator=integrator)
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    dr.kernel_history()
    render_scene(scene, WHITTED_SPP, seed=2, integrator=integrator)
    return sum(1 for k in dr.kernel_history() if str(k.get("type", "")).endswith("JIT"))
