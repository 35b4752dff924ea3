r"""Sweeps of full renders: error against time per BSDF, variants, and render-time ratios.

* :func:`sweep_renders` — the Cornell box (:func:`phonglab.bench.cornell.render_setups`,
  32 px): RMSE against the cached high-sample reference (its own noise subtracted,
  :func:`phonglab.metrics.errors`) and steady render time against spp, for ``lambert`` vs
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

Every render goes through :func:`phonglab.render.render_scene` (one pass; its
``pass_seconds[0]`` is the timed wall time, image evaluated and copied).
"""

from __future__ import annotations

import math
from pathlib import Path

import drjit as dr
import mitsuba as mi
import numpy as np

from .. import registration
from ..metrics import errors
from ..references import Reference
from ..render import render_scene
from ..scenes import load_scene
from .config import (RATIO_COMPARISONS, RATIO_RES, VARIANT, VARIANT_RES, WHITTED_SCENES, WHITTED_SPP,
                     Config)
from .cornell import CornellSpec, ratio_spec, render_jit, render_setups, timed_render
from .csvlog import open_log, progress_bar


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


def sweep_renders(out: Path, cfg: Config, cache: Path | None = None, progress: bool = True) -> None:
    """RMSE against the reference and steady time against spp, per BSDF, on the Cornell box."""
    registration.register(VARIANT)
    log, jit = open_log(out, "results"), open_log(out, "jit")
    setups = render_setups()
    total = sum(len(v) for v in setups.values()) * len(cfg.render_spps)
    bar = progress_bar(total, "renders", progress)
    for scene_name, methods in setups.items():
        for method, (spec, ref_spec) in methods.items():
            ref = ref_spec.reference(cfg.reference_spp, VARIANT, cache)
            scene = spec.load(VARIANT)
            first, ms, kernels, hits = render_jit(scene, 1, seed=7)
            steady = float(np.median([timed_render(scene, 1, seed=8 + r) for r in range(cfg.repeats)]))
            if not jit.has(group="render", method=method, scene=scene_name, variant=VARIANT):
                jit.add(dict(group="render", method=method, scene=scene_name, variant=VARIANT,
                             first_call_s=first, steady_s=steady, compile_ms=ms, kernels=kernels,
                             cache_hits=hits))
            for spp in cfg.render_spps:
                bar.update()
                if log.has(group="render", method=method, scene=scene_name, variant=VARIANT,
                           samples=spp):
                    continue
                log.add(dict(group="render", method=method, scene=scene_name, variant=VARIANT,
                             first_call_s=first, reference=f"{ref_spec.boxes} {cfg.reference_spp} spp",
                             **measure_render(scene, spp, cfg.repeats, ref)))
    bar.close()


def sweep_variants(out: Path, cfg: Config, cache: Path | None = None, progress: bool = True) -> list[str]:
    """llvm_ad_rgb against scalar_rgb (and cuda_ad_rgb with a GPU) on a 16 px Cornell box.

    Returns notes (e.g. why cuda_ad_rgb was skipped).
    """
    notes = []
    variants = [VARIANT, "scalar_rgb"]
    if dr.has_backend(dr.JitBackend.CUDA):
        variants.append("cuda_ad_rgb")
    else:
        notes.append("cuda_ad_rgb skipped: Dr.Jit found no CUDA device on this machine.")
    log, jit = open_log(out, "results"), open_log(out, "jit")
    scene_name = f"cornell-{VARIANT_RES}px"
    ref = CornellSpec(walls="diffuse", boxes="diffuse", res=VARIANT_RES).reference(
        cfg.reference_spp, VARIANT, cache)
    bar = progress_bar(len(variants) * 2 * len(cfg.variant_spps), "variants", progress)
    try:
        for variant in variants:
            registration.register(variant)
            for method in ("lambert", "diffuse"):
                scene = CornellSpec(walls=method, boxes=method, res=VARIANT_RES).load(variant)
                first = timed_render(scene, 1, seed=7)
                steady = float(np.median([timed_render(scene, 1, seed=8 + r) for r in range(cfg.repeats)]))
                if not jit.has(group="variant", method=method, scene=scene_name, variant=variant):
                    jit.add(dict(group="variant", method=method, scene=scene_name, variant=variant,
                                 first_call_s=first, steady_s=steady))
                for spp in cfg.variant_spps:
                    bar.update()
                    if log.has(group="variant", method=method, scene=scene_name, variant=variant,
                               samples=spp):
                        continue
                    log.add(dict(group="variant", method=method, scene=scene_name, variant=variant,
                                 first_call_s=first,
                                 reference=f"diffuse {cfg.reference_spp} spp {VARIANT}",
                                 **measure_render(scene, spp, cfg.repeats, ref)))
    finally:
        registration.register(VARIANT)
        bar.close()
    return notes


def sweep_ratios(out: Path, cfg: Config, progress: bool = True) -> None:
    """Alternating A/B render timings (ABBA order) for the render-time targets."""
    registration.register(VARIANT)
    log = open_log(out, "ratios")
    spp = cfg.ratio_spp
    bar = progress_bar(len(RATIO_COMPARISONS) * cfg.ratio_pairs, "ratios", progress)
    for name, a, b, which in RATIO_COMPARISONS:
        scenes = {m: ratio_spec(m, which).load(VARIANT) for m in (a, b)}
        for m in (a, b):                  # warm-up (JIT) excluded from the pairs
            timed_render(scenes[m], spp, seed=1)
        for pair in range(cfg.ratio_pairs):
            bar.update()
            if log.has(comparison=name, pair=pair):
                continue
            order = (a, b) if pair % 2 == 0 else (b, a)
            t = {m: timed_render(scenes[m], spp, seed=1000 + pair) for m in order}
            log.add(dict(comparison=name, a=a, b=b, pair=pair, scene=f"cornell {RATIO_RES}px {which}",
                         variant=VARIANT, spp=spp, t_a=t[a], t_b=t[b], ratio=t[a] / t[b]))
    bar.close()


def sweep_whitted_units(out: Path, cfg: Config, progress: bool = True) -> None:
    """ABBA pairs of ``whitted`` renders in graphics and in radiance units, same scene and spp
    (the kernels compiled beforehand); each row also records the kernels each render launched."""
    registration.register(VARIANT)
    log = open_log(out, "whitted")
    bar = progress_bar(len(WHITTED_SCENES) * cfg.ratio_pairs, "whitted units", progress)
    for name in WHITTED_SCENES:
        scene = load_scene(name, VARIANT)
        settings = scene.integrator().parameters()
        units = {u: mi.load_dict(dict(settings, units=u)) for u in ("graphics", "radiance")}
        kernels = {}
        for u, integrator in units.items():       # warm-up: tracing and JIT excluded
            kernels[u] = render_jit_integrator(scene, integrator)
        for pair in range(cfg.ratio_pairs):
            bar.update()
            if log.has(scene=name, pair=pair):
                continue
            order = ("graphics", "radiance") if pair % 2 == 0 else ("radiance", "graphics")
            t = {u: render_scene(scene, WHITTED_SPP, seed=1000 + pair,
                                 integrator=units[u]).pass_seconds[0] for u in order}
            log.add(dict(scene=name, pair=pair, spp=WHITTED_SPP, t_graphics=t["graphics"],
                         t_radiance=t["radiance"], ratio=t["graphics"] / t["radiance"],
                         kernels_graphics=kernels["graphics"], kernels_radiance=kernels["radiance"]))
    bar.close()


def render_jit_integrator(scene, integrator) -> int:
    """JIT kernels launched by one render of ``scene`` with ``integrator`` (after a warm-up)."""
    render_scene(scene, WHITTED_SPP, seed=1, integrator=integrator)
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    dr.kernel_history()
    render_scene(scene, WHITTED_SPP, seed=2, integrator=integrator)
    return sum(1 for k in dr.kernel_history() if str(k.get("type", "")).endswith("JIT"))
