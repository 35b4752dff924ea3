"""Planner benchmark: planned render vs the default configuration, at equal error, side by side.

For each scene (at a common resolution):

1. a converged reference (max_depth -1, many spp; phonglab.references, cached in
   .bench_cache/references);
2. the default configuration, llvm_ad_rgb with max_depth 8 and the scene's spp: its relative
   RMSE E_def against the reference (mean over repeats with different seeds);
3. ``planner.plan(scene, target_error=E_def)``: the planned variant, depth and spp;
4. timing: both configurations are rendered alternately ``--repeats`` times (one pass of
   phonglab.render.render_scene each, kernels compiled beforehand, so JIT time is excluded) and
   their median wall times are compared; each timed image also gives an error sample
   (phonglab.metrics.relative_rmse, the reference's noise subtracted).

Reported per scene: both configurations, the predicted and achieved error and time of the plan,
the speed-up (median time of default / planned) and the pilot's own cost. Results are printed
as a Markdown table and written to .bench_cache/planner_bench.json.

Run: ``.venv/bin/python scripts/planner_bench.py [--res 128] [--repeats 5] [scene ...]``
(``make bench-planner``).
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

import mitsuba as mi
import numpy as np

from phonglab import metrics, planner, references, render, runtime, scenes

SCENES = ["gray_direct", "gray_room", "cornell_phong", "glass_slab"]
DEFAULT_VARIANT = "llvm_ad_rgb"
DEFAULT_DEPTH = 8


def timed_render(scene, spp: int, seed: int, integrator, variant: str) -> tuple[np.ndarray, float]:
    """One pass of render.render_scene in ``variant`` (set first, outside the timing); (image,
    wall seconds of mi.render, evaluation and the copy to numpy)."""
    if mi.variant() != variant:
        runtime.set_variant(variant)
    result = render.render_scene(scene, spp, seed=seed, integrator=integrator)
    return result.image, result.pass_seconds[0]


def bench_scene(name: str, res: int, repeats: int, ref_factor: int) -> dict:
    params = {"res": res}
    info = scenes.inspect_scene(name, **params)
    # Default configuration: rgb, depth 8, the scene's spp.
    with runtime.quiet_mitsuba():
        scene_def = scenes.load_scene(info.path, DEFAULT_VARIANT, **params)
    spp_def = int(scene_def.sensors()[0].sampler().sample_count())
    pilot_def = planner.plan(info.path, 0.05, variant=DEFAULT_VARIANT, max_depth=DEFAULT_DEPTH,
                             spp=spp_def, params=params)
    # Reference, converged well below the errors compared (its own noise is subtracted too).
    ref_spp = max(1024, ref_factor * spp_def)
    t0 = time.perf_counter()
    ref = references.reference(info.path, ref_spp, params=params)
    ref_seconds = time.perf_counter() - t0
    ref_noise = metrics.relative_noise(ref.image, ref.stderr)

    def error(image) -> float:
        return metrics.relative_rmse(image, ref.image, ref_stderr=ref.stderr)

    integ_def = scenes.path_integrator(DEFAULT_DEPTH, info)
    timed_render(scene_def, spp_def, 999, integ_def, DEFAULT_VARIANT)  # compile
    err_def = [error(timed_render(scene_def, spp_def, 100 + k, integ_def, DEFAULT_VARIANT)[0])
               for k in range(repeats)]
    e_def = float(np.mean(err_def))

    plan = planner.plan(info.path, e_def, params=params)
    with runtime.quiet_mitsuba():
        scene_plan = scenes.load_scene(info.path, plan.variant, **params)
    integ_plan = scenes.path_integrator(plan.max_depth, info)
    timed_render(scene_plan, plan.spp, 998, integ_plan, plan.variant)  # compile
    # Alternate the two configurations so that load changes hit both alike.
    t_def, t_plan, err_plan = [], [], []
    for k in range(repeats):
        _, t = timed_render(scene_def, spp_def, 200 + k, integ_def, DEFAULT_VARIANT)
        t_def.append(t)
        img, t = timed_render(scene_plan, plan.spp, 300 + k, integ_plan, plan.variant)
        t_plan.append(t)
        err_plan.append(error(img))
    med_def, med_plan = statistics.median(t_def), statistics.median(t_plan)
    return {
        "scene": name, "res": res, "repeats": repeats,
        "reference": {"spp": ref.spp, "noise": ref_noise, "seconds": ref_seconds},
        "default": {"variant": DEFAULT_VARIANT, "max_depth": DEFAULT_DEPTH, "spp": spp_def,
                    "error": e_def, "error_sd": float(np.std(err_def, ddof=1)),
                    "seconds_median": med_def, "seconds": t_def,
                    "predicted_error": pilot_def.predicted_error},
        "planned": {"variant": plan.variant, "max_depth": plan.max_depth, "spp": plan.spp,
                    "target_error": e_def, "predicted_error": plan.predicted_error,
                    "error": float(np.mean(err_plan)),
                    "error_sd": float(np.std(err_plan, ddof=1)),
                    "predicted_seconds_one_pass": plan.seconds_per_pass
                    + plan.seconds_per_sample * plan.resolution[0] * plan.resolution[1] * plan.spp,
                    "seconds_median": med_plan, "seconds": t_plan,
                    "pilot_seconds": plan.pilot_seconds, "reasons": plan.reasons},
        "speedup": med_def / med_plan,
        # Monte Carlo efficiency 1/(time x error²) [Veach 1997, §2.4.3; PBRT 4th ed., §2.1.4]:
        # the time ratio at exactly equal error when the error is noise-dominated.
        "efficiency_ratio": (med_def * e_def ** 2) / (med_plan * float(np.mean(err_plan)) ** 2),
        "speedup_with_pilot": med_def / (med_plan + plan.pilot_seconds),
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenes", nargs="*", default=SCENES)
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--ref-factor", type=int, default=64,
                    help="reference spp = max(1024, factor x scene spp)")
    ap.add_argument("--out", default=str(references.CACHE_DIR / "planner_bench.json"))
    args = ap.parse_args(argv)
    rows = []
    for name in args.scenes:
        rows.append(bench_scene(name, args.res, args.repeats, args.ref_factor))
        print(json.dumps({k: rows[-1][k] for k in ("scene", "speedup")}), flush=True)
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(rows, indent=2))
    print(planner.benchmark_table(rows))
    for r in rows:
        print(f"\n{r['scene']}: reference {r['reference']['spp']} spp (noise "
              f"{r['reference']['noise']:.4f}, {r['reference']['seconds']:.1f} s); plan reasons:")
        for reason in r["planned"]["reasons"]:
            print(f"  - {reason}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
