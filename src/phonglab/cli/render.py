"""``phonglab render``: render a scene to a float EXR with provenance and a PNG preview.

Lazy imports: the modules that pull in Mitsuba, matplotlib or numpy (render, scenes, planner,
references, metrics) are imported inside :func:`run` and :func:`run_planned`, because
``phonglab`` builds every subcommand's parser at start-up and importing them there would cost
every command, ``--help`` included, one to two seconds (``python -X importtime -c 'import
phonglab.render'``).
"""

from __future__ import annotations

import argparse
import math
import statistics
from pathlib import Path

from .. import runtime
from ..errors import PhonglabError
from .options import add_scene_params


def add_parser(sub) -> None:
    p = sub.add_parser(
        "render", help="render a scene to EXR + PNG",
        description="Render a Mitsuba XML scene (phonglab's plugins registered) to a float "
                    "OpenEXR file with its provenance in the header, and a PNG preview.",
        epilog="examples:\n  phonglab render scenes_xml/cornell_phong.xml --spp 128 -o out/cornell.exr\n"
               "  phonglab render cornell_phong --target-error 0.02   (planned: see 'phonglab plan')\n"
               "  phonglab render gray_direct --adaptive --target-error 0.01 --max-seconds 60",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene", help="scene XML file, or a name from scenes_xml/ (e.g. cornell_phong)")
    p.add_argument("--spp", type=int, default=None, help="samples per pixel (default: the scene's)")
    p.add_argument("--variant", default=None, help="Mitsuba variant (default: llvm_ad_rgb)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--max-depth", type=int, default=None, help="path length limit (default: the scene's)")
    p.add_argument("--max-seconds", type=float, default=None, metavar="S",
                   help="with --target-error: refuse a plan predicted to take longer (default: "
                        "planner.MAX_SECONDS, one hour; 'inf' allows any); with --adaptive: "
                        "stop adding passes after S seconds")
    p.add_argument("-o", "--output", default=None, help="output EXR (default: out/<scene>.exr)")
    p.add_argument("--target-error", type=float, default=None, metavar="E",
                   help="plan variant, max_depth and spp for this relative RMSE (see 'phonglab "
                        "plan'); --spp/--variant/--max-depth given explicitly override the plan")
    p.add_argument("--adaptive", action="store_true",
                   help="with --target-error: adaptive sampling (docs/adaptive.md): after a "
                        "pilot, trace rays only where the estimated error exceeds its budget; "
                        "writes the spp map beside the EXR (<out>.spp.exr, <out>.spp.png)")
    p.add_argument("--max-spp", type=int, default=None, metavar="N",
                   help="with --adaptive: at most N samples in any pixel")
    add_scene_params(p)
    p.set_defaults(func=run)


def run(args) -> int:
    from ..render import render_file
    from ..scenes import scene_path

    path = scene_path(args.scene)
    out = Path(args.output or Path("out") / (path.stem + ".exr"))
    if out.is_dir() or out.suffix.lower() != ".exr":
        raise PhonglabError(f"-o {out}: the output must be a file name ending in .exr "
                            f"(e.g. -o out/{path.stem}.exr); the PNG preview is written beside it")
    if args.adaptive or args.max_spp is not None:
        return run_adaptive(args, path, out)
    if args.target_error is not None:
        return run_planned(args, path, out)
    result = render_file(path, out, spp=args.spp, variant=args.variant, seed=args.seed,
                         max_depth=args.max_depth, params=dict(args.params))
    meta = result.metadata
    print(f"rendered {path} with {meta['spp']} spp in {meta['variant']} "
          f"({result.seconds:.2f} s, first pass {result.pass_seconds[0]:.2f} s incl. JIT)")
    _print_files(out, result)
    return 0


def run_planned(args, path: Path, out: Path) -> int:
    """Plan for --target-error, render the plan, report predicted and achieved error and time."""
    from .. import metrics, planner
    from ..outputs import RenderOutputs
    from ..render import render_file

    RenderOutputs.beside(out).check()       # before the pilot, not only before the render
    plan = planner.plan(path, args.target_error, variant=args.variant,
                        max_depth=args.max_depth, spp=args.spp,
                        max_seconds=args.max_seconds, params=dict(args.params))
    print(plan.summary())
    meta = {"target_error": plan.target_error, "predicted_error": plan.predicted_error,
            "predicted_seconds": plan.predicted_seconds, "planned": plan.to_dict()}
    if plan.uses_wavefront:
        return _render_plan_wavefront(args, path, out, plan, meta)
    with runtime.quiet_mitsuba():
        result = render_file(path, out, seed=args.seed, extra_metadata=meta,
                             params=plan.params, **plan.render_kwargs())
    times = result.pass_seconds
    # Steady state: the first pass may include JIT compilation; count it as a median pass.
    steady = statistics.median(times[1:]) * len(times) if len(times) > 1 else result.seconds
    print(f"rendered {path} with {result.metadata['spp']} spp ({plan.sampler} sampler), "
          f"max_depth {plan.max_depth} in {plan.variant}: "
          f"{result.seconds:.3g} s ({steady:.3g} s steady state; predicted "
          f"{plan.chosen_seconds:.3g} s)")
    achieved = _reference_error(path, plan, result.image)
    if achieved is not None:
        err, ref_spp = achieved
        print(f"  error: achieved {err:.4g} against the cached reference ({ref_spp} "
              f"spp, max_depth -1); predicted {plan.predicted_error:.4g}, target "
              f"{plan.target_error:g}")
    elif result.stderr is not None:
        noise = metrics.relative_noise(result.image, result.stderr)
        err = math.hypot(noise, plan.predicted_bias)
        print(f"  error: about {err:.4g} (noise {noise:.4g} estimated from {len(times)} passes, "
              f"depth bias {plan.predicted_bias:.3g} from the pilot; no cached reference: make "
              f"one with 'phonglab plan {path} --make-reference 4096'); predicted "
              f"{plan.predicted_error:.4g}, target {plan.target_error:g}")
    else:
        print(f"  error: not measurable from one pass; predicted {plan.predicted_error:.4g}, "
              f"target {plan.target_error:g}")
    _print_files(out, result)
    return 0


def _render_plan_wavefront(args, path: Path, out: Path, plan, meta: dict) -> int:
    """Render a plan whose model or sampling goes through phonglab.adaptive; report the error."""
    from .. import adaptive
    from ..planner import choice

    uniform = plan.sampling == "uniform"
    spp = max(2, math.ceil(plan.chosen_spp))
    integrator = None if plan.model == "path" else choice.model_dict(plan.model, plan.max_depth,
                                                                     path, plan.params)
    meta = dict(meta, max_depth=plan.max_depth, model=plan.model, sampling=plan.sampling)
    with runtime.quiet_mitsuba():
        result = adaptive.render_file_adaptive(
            path, out, plan.noise_target, variant=plan.variant, seed=args.seed,
            max_depth=plan.max_depth, params=plan.params, integrator=integrator,
            min_spp=spp if uniform else adaptive.MIN_SPP, max_spp=spp if uniform else None,
            extra_metadata=meta)
    print(f"rendered {path} with {plan.model}, {plan.sampling} sampling, max_depth "
          f"{plan.max_depth} in {plan.variant}: {result.total_spp:.1f} spp on average, "
          f"{result.seconds:.3g} s (predicted {plan.chosen_seconds:.3g} s steady state)")
    achieved = _reference_error(path, plan, result.image)
    if achieved is not None:
        err, ref_spp = achieved
        print(f"  error: achieved {err:.4g} against the cached reference ({ref_spp} spp); "
              f"estimated {math.hypot(result.estimated_error, plan.predicted_bias):.4g}, "
              f"target {plan.target_error:g}")
    else:
        print(f"  error: estimated {math.hypot(result.estimated_error, plan.predicted_bias):.4g}"
              f" (noise {result.estimated_error:.4g} from the samples, depth bias "
              f"{plan.predicted_bias:.3g} from the pilot); target {plan.target_error:g}")
    _print_files(out, result)
    print(f"  spp map: {', '.join(str(p) for p in adaptive.spp_paths(out))}")
    return 0


def _reference_error(path: Path, plan, image) -> tuple[float, int] | None:
    """(relative RMSE of ``image`` against the cached reference of the planned scene, that
    reference's spp), or None when no reference is cached."""
    from .. import metrics, references

    ref = references.cached(path, params=plan.params,
                            variant=references.variant_for_color(plan.color))
    if ref is None:
        return None
    return metrics.relative_rmse(image, ref.image, ref_stderr=ref.stderr), ref.spp


def run_adaptive(args, path: Path, out: Path) -> int:
    """--adaptive --target-error E: adaptive sampling to E, the spp map beside the image."""
    if not args.adaptive:
        raise PhonglabError("--max-spp applies to adaptive sampling; add --adaptive "
                            "--target-error E (or use --spp for a uniform render)")
    if args.target_error is None:
        raise PhonglabError("--adaptive needs --target-error E, the relative RMSE to reach "
                            "(e.g. --target-error 0.02)")
    if args.spp is not None:
        raise PhonglabError("--adaptive chooses the samples per pixel itself; drop --spp (cap "
                            "them with --max-spp N)")
    from .. import adaptive   # lazy: imports Mitsuba
    with runtime.quiet_mitsuba():
        result = adaptive.render_file_adaptive(
            path, out, args.target_error, variant=args.variant, seed=args.seed,
            max_seconds=args.max_seconds, max_spp=args.max_spp, max_depth=args.max_depth,
            params=dict(args.params))
    meta = result.metadata
    why = {"target": "the estimated error meets the target",
           "max_spp": "pixels reached --max-spp", "max_seconds": "--max-seconds ran out"}
    print(f"rendered {path} adaptively in {meta['variant']}: {len(result.passes)} passes, "
          f"{result.total_spp:.1f} spp on average ({meta['spp_min']} to {meta['spp_max']}), "
          f"{result.seconds:.3g} s; estimated relative RMSE {result.estimated_error:.4g} "
          f"(target {args.target_error:g}); stopped: {why[result.stopped]}")
    _print_files(out, result)
    spp_exr, spp_png = adaptive.spp_paths(out)
    print(f"  spp map: {spp_exr} (channel Y), {spp_png}")
    return 0


def _print_files(out: Path, result) -> None:
    """Where the EXR and its PNG preview are (and the preview's exposure when not 0)."""
    print(f"  EXR: {out}")
    ev = result.metadata.get("preview_exposure_ev", 0.0)
    note = f" (exposure {ev:+.1f} EV: the image exceeds 1, as graphics units do)" if ev else ""
    print(f"  PNG: {out.with_suffix('.png')}{note}")
