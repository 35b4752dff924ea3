"""Planner benchmark: the planned command vs the default configuration at equal error, whole-command wall time.

For each scene (parameters in :data:`SCENES`, a target error E each):

1. a converged reference (max_depth -1, phonglab.engine.references, cached in .bench_cache/references),
   its relative noise at most E/3 (:func:`bench_reference`);
2. the **default configuration** (llvm_ad_rgb, the scene's path integrator at max_depth 8,
   uniform spp) with its spp *raised until it reaches E*: a fit of e(N)² = b² + c/N (its
   depth bias and its noise) to the errors measured so far gives the next N, until the error
   is within 2 % of E (:func:`equal_error_spp`);
3. timing, after one untimed run of each (JIT kernels then come from Dr.Jit's on-disk cache
   for both, as on a user's second run), alternating, ``--repeats`` times with different
   seeds: each configuration runs as a
   **fresh process** (Python start, imports, scene load, JIT kernels, the pilot and planning
   for the planned one, the render, the files written), timed from the parent around the whole
   process.  The processes *are* the commands a user types: ``phonglab render SCENE --spp N
   --max-depth 8 --variant llvm_ad_rgb -D res=R`` (default) and ``phonglab render SCENE
   --target-error E -D res=R`` (planned: ``planner.plan``, the render the plan chose, its
   error against the cached reference printed), each writing what the command writes (EXR,
   standard-error EXR, PNG preview; the spp map too for an adaptive plan).  What the plan
   chose is read back from the planned EXR's header.
4. each process's image is compared with the reference (relative RMSE, the reference's noise
   subtracted).

Reported per scene: the plan (model, sampling, variant, depth, spp), both errors, both wall
times (median, min-max over seeds), the speed-up T_default/T_planned with its spread, and the
plan's reasons.  Written to ``--out`` (JSON) and printed as a table.

Each row also records what it cost the bench (``bench_seconds``: reference, calibration,
warm-ups and repeats) and its date; the JSON is written after every row, so an interrupted
run keeps what it finished, and ``--merge`` keeps the rows of ``--out`` this run does not
redo (the 512² rows, ``make bench-planner-512``, are run a few scenes at a time).

Run: ``.venv/bin/python scripts/planner_bench.py [--res 128 256] [--repeats 3] [--merge]
[scene ...]`` (``make bench``, ``make bench-planner``, ``make bench-planner-512``).
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from phonglab import planner, runtime

from phonglab.engine import exr, metrics, references, render, scenes
from phonglab.bench import timing
from phonglab.planner import benchmark
from phonglab.engine.outputs import check_output_file, write_json
from phonglab.errors import PhonglabError

#: The default configuration: ``phonglab render``'s default variant, path at max_depth 8.
DEFAULT_VARIANT = "llvm_ad_rgb"
DEFAULT_DEPTH = 8

#: scene -> (target error E, scene parameters at the bench resolution R)
SCENES = {
    "gray_direct": (0.005, lambda r: {"res": r}),
    "gray_room": (0.01, lambda r: {"res": r}),
    "cornell_phong": (0.02, lambda r: {"res": r}),
    "glass_slab": (0.05, lambda r: {"res": r}),
    "nb_sphere_row": (0.005, lambda r: {"width": 4 * r, "height": r}),
    # held out: no planner setting is tuned on them, and they are reported apart from the
    # rows the planner is tuned on
    "textured_room": (0.02, lambda r: {"res": r}),
    "outdoor_envmap": (0.01, lambda r: {"res": r}),
}
#: The scenes the planner was never tuned on (:data:`SCENES`).
HELD_OUT = ("textured_room", "outdoor_envmap")
#: The ``phonglab`` command of this interpreter's environment (its console script).
PHONGLAB = Path(sys.executable).with_name("phonglab")


def command(kind: str, scene: str, params: dict, value, seed: int, out: Path) -> list[str]:
    """The ``phonglab render`` command line of the default (``value`` = spp) or planned
    (``value`` = E) configuration."""
    base = [str(PHONGLAB)] if PHONGLAB.exists() else [sys.executable, "-m", "phonglab.cli"]
    cmd = base + ["render", scene, "-o", str(out), "--seed", str(seed)]
    cmd += [a for k, v in params.items() for a in ("-D", f"{k}={v}")]
    if kind == "default":
        return cmd + ["--spp", str(value), "--max-depth", str(DEFAULT_DEPTH),
                      "--variant", DEFAULT_VARIANT]
    return cmd + ["--target-error", str(value)]


def run_child(kind: str, scene: str, params: dict, value, seed: int, out: Path) -> tuple[float, dict]:
    """Wall time of one fresh ``phonglab render`` process, and what its EXR header records
    (for a planned one: the plan and the samples the render took)."""
    seconds = timing.run_child(command(kind, scene, params, value, seed, out), capture=True).seconds
    meta = exr.read(out)[1]
    if kind == "default":
        return seconds, {"spp": meta["spp"]}
    plan = meta["planned"]   # exr.read decodes every header value from JSON
    spp = meta.get("spp_mean", meta.get("spp"))
    return seconds, {"model": plan["model"], "sampling": plan["sampling"],
                     "variant": plan["variant"], "sampler": plan["sampler"],
                     "max_depth": plan["max_depth"], "spp": float(spp),
                     "uniform_path_spp": plan["spp"], "pilot_seconds": plan["pilot_seconds"],
                     "reused_spp": plan.get("reused_spp", 0),
                     "predicted_seconds": plan["chosen_seconds"], "reasons": plan["reasons"]}


# --- the comparison -----------------------------------------------------------------------------

def default_error(scene: str, params: dict, spp: int, ref, seeds) -> float:
    """Mean relative RMSE of the default configuration at ``spp`` over ``seeds`` (in-process)."""
    info = scenes.inspect_scene(scene, **params)
    with runtime.quiet_mitsuba():
        loaded = scenes.load_scene(info.path, DEFAULT_VARIANT, **params)
    integ = scenes.path_integrator(DEFAULT_DEPTH, info)
    errs = [metrics.relative_rmse(render.render_scene(loaded, spp, seed=s, integrator=integ).image,
                                  ref.image, ref_stderr=ref.stderr) for s in seeds]
    return float(np.mean(errs))


#: Reference samples per pixel at 128² and below.
REF_SPP = 4096


def reference_spp(res: int) -> int:
    """Reference spp of the bench at resolution ``res``: :data:`REF_SPP` up to 128², then the
    same samples per image, at least 1024 spp (its noise, known from its passes, is subtracted
    from every error measured against it)."""
    return max(1024, min(REF_SPP, REF_SPP * 128 * 128 // (res * res)))


#: A reference's relative noise may be at most this fraction of E: its noise is subtracted from
#: every error measured against it (known from its passes), but that estimate is itself noisy,
#: and at 4096 spp nb_sphere_row's reference at 128² was 0.0044 noisy for E = 0.005 (0.0085 at
#: 256²): the measured errors were mostly the reference's.
REF_NOISE_FRACTION = 1 / 3
#: Most spp a bench reference is given (nb_sphere_row 1024×256 needs 32768).
MAX_REF_SPP = 65536


def bench_reference(name: str, params: dict, target: float, spp: int):
    """The scene's reference (phonglab.engine.references, cached) at ``spp`` samples or more: doubled
    until its relative noise is at most :data:`REF_NOISE_FRACTION` of ``target`` (the spp its
    noise predicts, ∝ 1/√spp, rounded up to a power of two), at most :data:`MAX_REF_SPP`."""
    ref = references.reference(name, spp, params=params)
    noise = metrics.relative_noise(ref.image, ref.stderr)
    while noise > REF_NOISE_FRACTION * target and ref.spp < MAX_REF_SPP:
        want = ref.spp * (noise / (REF_NOISE_FRACTION * target)) ** 2
        ref = references.reference(name, min(MAX_REF_SPP, 1 << math.ceil(math.log2(want))),
                                   params=params)
        noise = metrics.relative_noise(ref.image, ref.stderr)
    return ref


#: Most spp the default configuration is given when it cannot reach E (a depth-8 bias floor).
MAX_DEFAULT_SPP = 8192
#: The calibration stops once the default's measured error is within this fraction of E.
CALIBRATION_TOLERANCE = 0.02
#: Seeds of the calibration's renders, two per round (fresh ones each round).
CALIBRATION_SEEDS = ((11, 12), (13, 14), (15, 16), (17, 18), (19, 20))


def equal_error_spp(scene: str, params: dict, target: float, ref) -> tuple[int, float, list]:
    """The default configuration's spp that reaches ``target``: (spp, its measured error,
    every (spp, error) measured).

    Starts at 64 spp; each round fits e(N)² = b² + c/N (depth bias and noise,
    :func:`phonglab.planner.benchmark.fit_error_model`) to every point so far, renders at the
    N that model gives for E, and stops once the error is within
    :data:`CALIBRATION_TOLERANCE` of E.  Capped at :data:`MAX_DEFAULT_SPP` (then its error
    stays above the target, and the table shows it).
    """
    spp, points = 64, []
    for seeds in CALIBRATION_SEEDS:
        err = default_error(scene, params, spp, ref, seeds)
        points.append((spp, err))
        if len(points) > 1 and abs(err - target) <= CALIBRATION_TOLERANCE * target:
            break
        want = benchmark.spp_for_error(*benchmark.fit_error_model(points), target)
        nxt = int(min(max(1, math.ceil(want)), MAX_DEFAULT_SPP)) if math.isfinite(want) \
            else MAX_DEFAULT_SPP
        if nxt == spp:
            break
        spp = nxt
    spp, err = points[-1]   # every way out: the last render made (the next N is not rendered)
    return spp, err, points


def bench_scene(name: str, res: int, repeats: int, ref_spp: int, workdir: Path) -> dict:
    target, make_params = SCENES.get(name, (0.02, lambda r: {"res": r}))
    params = make_params(res)
    t0 = time.perf_counter()
    ref = bench_reference(name, params, target, ref_spp)
    ref_seconds = time.perf_counter() - t0
    spp_def, err_cal, calibration = equal_error_spp(name, params, target, ref)

    def error(path: Path) -> float:
        return metrics.relative_rmse(exr.read_image(path), ref.image, ref_stderr=ref.stderr)

    t_def, t_plan, e_def, e_plan, plan_info = [], [], [], [], None
    # One untimed run of each first: both timed commands then find their JIT kernels in
    # Dr.Jit's on-disk cache, as a user's second run does (the calibration above compiles the
    # default's kernel and nothing compiles the planned command's: without this its first
    # repeat paid 0.15-0.7 s of compilation the default did not, measured).
    run_child("default", name, params, spp_def, 199, workdir / f"{name}-warm.def.exr")
    run_child("planned", name, params, target, 299, workdir / f"{name}-warm.plan.exr")
    for k in range(repeats):
        out = workdir / f"{name}-{k}"
        t, _ = run_child("default", name, params, spp_def, 200 + k, out.with_suffix(".def.exr"))
        t_def.append(t)
        e_def.append(error(out.with_suffix(".def.exr")))
        t, plan_info = run_child("planned", name, params, target, 300 + k,
                                 out.with_suffix(".plan.exr"))
        t_plan.append(t)
        e_plan.append(error(out.with_suffix(".plan.exr")))
    ratios = [d / p for d, p in zip(t_def, t_plan)]
    row = {
        "scene": name, "res": res, "params": params, "target_error": target, "repeats": repeats,
        "held_out": name in HELD_OUT,
        "reference": {"spp": ref.spp, "noise": metrics.relative_noise(ref.image, ref.stderr),
                      "seconds": ref_seconds},
        "default": {"variant": DEFAULT_VARIANT, "max_depth": DEFAULT_DEPTH, "spp": spp_def,
                    "calibration_error": err_cal, "calibration": calibration,
                    "error": float(np.mean(e_def)), "errors": e_def,
                    "error_sd": float(np.std(e_def, ddof=1)) if repeats > 1 else 0.0,
                    "seconds": t_def, "seconds_median": statistics.median(t_def)},
        "planned": {**plan_info, "error": float(np.mean(e_plan)), "errors": e_plan,
                    "error_sd": float(np.std(e_plan, ddof=1)) if repeats > 1 else 0.0,
                    "seconds": t_plan, "seconds_median": statistics.median(t_plan)},
        "speedup": statistics.median(t_def) / statistics.median(t_plan),
        "speedup_min": min(ratios), "speedup_max": max(ratios),
    }
    row["equal_error_speedup"] = benchmark.equal_error_speedup(row)
    return row


def merged_rows(path: Path, fresh: list[dict]) -> list[dict]:
    """The rows of ``path`` (a previous run's JSON) that ``fresh`` does not replace (same
    scene and resolution), then ``fresh``: a run over some scenes keeps the others' rows."""
    done = {(r["scene"], r["res"]) for r in fresh}
    old = json.loads(path.read_text()) if path.is_file() else []
    return [r for r in old if (r["scene"], r["res"]) not in done] + fresh


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenes", nargs="*", default=list(SCENES))
    ap.add_argument("--res", type=int, nargs="+", default=[128],
                    help="bench resolutions R (every scene at each; a film of R x R, 4R x R "
                         "for nb_sphere_row)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--ref-spp", type=int, default=None,
                    help=f"reference spp (default {REF_SPP} at 128² and below, fewer on "
                         f"larger films: reference_spp())")
    ap.add_argument("--out", default=str(references.CACHE_DIR / "planner_bench.json"))
    ap.add_argument("--merge", action="store_true",
                    help="keep the rows of --out that this run does not redo (other scenes or "
                         "resolutions): the 512² rows are run a few scenes at a time")
    args = ap.parse_args(argv)
    unknown = [s for s in args.scenes if s not in SCENES]
    if unknown:
        print(f"planner_bench: unknown scene(s) {', '.join(unknown)}: choose from "
              f"{', '.join(SCENES)}.", file=sys.stderr)
        return 2
    try:   # before any render: an hour of 512² rows must not end in a file it cannot write
        out = check_output_file(args.out, "planner bench record (--out)")
    except PhonglabError as exc:
        print(f"planner_bench: {exc}.", file=sys.stderr)
        return 2
    rows = []
    with tempfile.TemporaryDirectory(prefix="planner-bench-") as tmp:
        for res in args.res:
            for name in args.scenes:
                ref_spp = args.ref_spp or reference_spp(res)
                t0 = time.perf_counter()
                row = bench_scene(name, res, args.repeats, ref_spp, Path(tmp))
                # what the row cost the bench (reference, calibration, warm-ups, repeats) and when
                row["bench_seconds"] = time.perf_counter() - t0
                row["date"] = time.strftime("%Y-%m-%d")
                rows.append(row)
                # written after every row: an interrupted run keeps the rows it finished
                write_json(out, merged_rows(out, rows) if args.merge else rows, indent=2)
                print(json.dumps({k: row[k] for k in ("scene", "res", "speedup",
                                                       "bench_seconds")}), flush=True)
    print(planner.benchmark_table(rows))
    for r in rows:
        print(f"\n{r['scene']}: plan reasons:")
        for reason in r["planned"]["reasons"]:
            print(f"  - {reason}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
