"""Planner benchmark: planned render vs the default configuration, at equal error, side by side.

For each scene (at a common resolution):

1. a converged reference (max_depth -1, many spp; cached in .bench_cache/references);
2. the default configuration, llvm_ad_rgb with max_depth 8 and the scene's spp: its relative
   RMSE E_def against the reference (mean over repeats with different seeds);
3. ``planner.plan(scene, target_error=E_def)``: the planned variant, depth and spp;
4. timing: both configurations are rendered alternately ``--repeats`` times (one mi.render call
   each, kernels compiled beforehand, so JIT time is excluded) and their median wall times are
   compared; each timed image also gives an error sample.

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

import numpy as np

from phonglab import planner, render

SCENES = ["gray_direct", "gray_room", "cornell_phong", "glass_slab"]
DEFAULT_VARIANT = "llvm_ad_rgb"
DEFAULT_DEPTH = 8


def timed_render(scene, spp: int, seed: int, integrator, variant: str) -> tuple[np.ndarray, float]:
    """Render in ``variant`` (set first, outside the timing); (image, wall seconds)."""
    import drjit as dr
    import mitsuba as mi

    if mi.variant() != variant:
        mi.set_variant(variant)
    t0 = time.perf_counter()
    img = mi.render(scene, spp=spp, seed=seed, integrator=integrator)
    dr.eval(img)
    arr = np.array(img, dtype=np.float64)
    return arr, time.perf_counter() - t0


def bench_scene(name: str, res: int, repeats: int, ref_factor: int) -> dict:
    params = {"res": res}
    info = planner.inspect_scene(name, **params)
    # Default configuration: rgb, depth 8, the scene's spp.
    with planner.quiet_mitsuba():
        scene_def = render.load_scene(name, DEFAULT_VARIANT, **params)
    spp_def = int(scene_def.sensors()[0].sampler().sample_count())
    # Reference, converged well below the errors compared (its own noise is subtracted too).
    pilot_def = planner.plan(name, 0.05, variant=DEFAULT_VARIANT, max_depth=DEFAULT_DEPTH,
                             spp=spp_def, params=params)
    ref_spp = max(1024, ref_factor * spp_def)
    t0 = time.perf_counter()
    ref, ref_se, _ = planner.make_reference(name, ref_spp, params=params)
    ref_seconds = time.perf_counter() - t0
    ref_noise = planner.noise_error(ref, ref_se)

    import mitsuba as mi

    mi.set_variant(DEFAULT_VARIANT)
    integ_def = planner._path_integrator(DEFAULT_DEPTH, info)
    timed_render(scene_def, spp_def, 999, integ_def, DEFAULT_VARIANT)  # compile
    err_def = [planner.achieved_error(timed_render(scene_def, spp_def, 100 + k, integ_def,
                                                   DEFAULT_VARIANT)[0],
                                      ref, ref_se) for k in range(repeats)]
    e_def = float(np.mean(err_def))

    plan = planner.plan(name, e_def, params=params)
    with planner.quiet_mitsuba():
        scene_plan = render.load_scene(name, plan.variant, **params)
    integ_plan = planner._path_integrator(plan.max_depth, info)
    timed_render(scene_plan, plan.spp, 998, integ_plan, plan.variant)  # compile
    # Alternate the two configurations so that load changes hit both alike.
    t_def, t_plan, err_plan = [], [], []
    for k in range(repeats):
        _, t = timed_render(scene_def, spp_def, 200 + k, integ_def, DEFAULT_VARIANT)
        t_def.append(t)
        img, t = timed_render(scene_plan, plan.spp, 300 + k, integ_plan, plan.variant)
        t_plan.append(t)
        err_plan.append(planner.achieved_error(img, ref, ref_se))
    med_def, med_plan = statistics.median(t_def), statistics.median(t_plan)
    return {
        "scene": name, "res": res, "repeats": repeats,
        "reference": {"spp": ref_spp, "noise": ref_noise, "seconds": ref_seconds},
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
    ap.add_argument("--out", default=str(planner.CACHE_DIR / "planner_bench.json"))
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
