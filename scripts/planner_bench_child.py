"""One command of the planner benchmark (scripts/planner_bench.py), as a fresh process.

``planner_bench_child.py default|planned SCENE PARAMS_JSON SPP|E SEED OUT.exr`` does what
``phonglab render SCENE --spp N --max-depth 8 --variant llvm_ad_rgb`` (default) or
``phonglab render SCENE --target-error E`` (planned) does, with scene parameters the CLI has
no option for, and prints a JSON line of what it did.  Its imports are the CLI's: the default
command never imports the planner (``cli/render.py`` imports it inside ``run_planned``), so
neither does :func:`child_default`; the parent times the whole process.
"""

from __future__ import annotations

import json
import math
import sys

from phonglab import exr, render, runtime, scenes

DEFAULT_VARIANT = "llvm_ad_rgb"
DEFAULT_DEPTH = 8


def child_default(scene: str, params: dict, spp: int, seed: int, out: str) -> dict:
    """What ``phonglab render SCENE --spp N --max-depth 8 --variant llvm_ad_rgb`` does."""
    info = scenes.inspect_scene(scene, **params)
    with runtime.quiet_mitsuba():
        loaded = scenes.load_scene(info.path, DEFAULT_VARIANT, **params)
    result = render.render_scene(loaded, spp, seed=seed, passes=min(spp, 8) if spp >= 16 else 1,
                                 integrator=scenes.path_integrator(DEFAULT_DEPTH, info))
    exr.write(out, result.image, {"spp": spp})
    return {"spp": spp}


def child_planned(scene: str, params: dict, target: float, seed: int, out: str) -> dict:
    """What ``phonglab render SCENE --target-error E`` does (cli/render.py, run_planned)."""
    from phonglab import adaptive, planner   # as cli/render.py: only where the plan is made
    from phonglab.planner import choice

    plan = planner.plan(scene, target, params=params)
    if plan.uses_wavefront:
        uniform = plan.sampling == "uniform"
        spp = max(2, math.ceil(plan.chosen_spp))
        integ = None if plan.model == "path" else choice.model_dict(plan.model, plan.max_depth,
                                                                    scene, params)
        with runtime.quiet_mitsuba():
            result = adaptive.render_file_adaptive(
                scene, out, plan.noise_target, variant=plan.variant, seed=seed,
                max_depth=plan.max_depth, params=params, integrator=integ,
                min_spp=spp if uniform else adaptive.MIN_SPP, max_spp=spp if uniform else None)
        spp_mean = result.total_spp
    else:
        info = scenes.inspect_scene(scene, **params)
        with runtime.quiet_mitsuba():
            loaded = scenes.load_scene(info.path, plan.variant, **params)
        kw = plan.render_kwargs()
        result = render.render_scene(loaded, kw["spp"], seed=seed, passes=kw["passes"],
                                     integrator=scenes.path_integrator(plan.max_depth, info),
                                     sensor=plan.uniform_sensor(info))
        spp_mean = int(sum(result.pass_spp))
        exr.write(out, result.image, {"spp": spp_mean})
    return {"model": plan.model, "sampling": plan.sampling, "variant": plan.variant,
            "sampler": plan.sampler,
            "max_depth": plan.max_depth, "spp": spp_mean, "uniform_path_spp": plan.spp,
            "pilot_seconds": plan.pilot_seconds, "predicted_seconds": plan.chosen_seconds,
            "reasons": plan.reasons}



def main(argv: list[str]) -> int:
    kind, scene, params, value, seed, out = argv[:6]
    fn = child_default if kind == "default" else child_planned
    report = fn(scene, json.loads(params), int(value) if kind == "default" else float(value),
                int(seed), out)
    print(json.dumps(report))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
