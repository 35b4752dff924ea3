"""``phonglab render``: render a scene to a float EXR with provenance and a PNG preview.

Lazy imports: the modules that pull in Mitsuba, matplotlib or numpy (render, scenes, planner,
adaptive) are imported inside :func:`run`, :func:`run_planned` and :func:`run_adaptive`, because
``phonglab`` builds every subcommand's parser at start-up and importing them there would cost
every command, ``--help`` included, one to two seconds (``python -X importtime -c 'import
phonglab.engine.render'``).
"""

from __future__ import annotations

import argparse
import statistics
from pathlib import Path

from .. import runtime
from ..errors import PhonglabError
from ..settings import check_max_seconds
from .options import add_plugin, add_scene_params, add_seed, check_plugin_files


def add_parser(sub) -> None:
    p = sub.add_parser(
        "render", help="render a scene to EXR + PNG",
        description="Render a Mitsuba XML scene (phonglab's plugins registered) to a float "
                    "OpenEXR file with its provenance in the header, and a PNG preview.",
        epilog="examples:\n  phonglab render cornell_phong --spp 128 -o out/cornell.exr\n"
               "  phonglab render cornell_phong --target-error 0.02   (planned: see 'phonglab plan')\n"
               "  phonglab render gray_direct --adaptive --target-error 0.01 --max-seconds 60\n"
               "  phonglab render myscene.xml --plugin mybsdf.py   (a scene with your own BSDF)",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene", help="scene XML file, or the name of a scene phonglab ships (e.g. cornell_phong)")
    p.add_argument("--spp", type=int, default=None, help="samples per pixel (default: the scene's)")
    p.add_argument("--variant", default=None, help="Mitsuba variant (default: llvm_ad_rgb)")
    add_seed(p)
    p.add_argument("--max-depth", type=int, default=None, help="path length limit (default: the scene's)")
    p.add_argument("--max-seconds", type=float, default=None, metavar="S",
                   help="with --target-error: refuse a plan predicted to take longer (default: "
                        "planner.MAX_SECONDS, one hour; 'inf' allows any); with --adaptive: "
                        "stop adding passes after S seconds")
    p.add_argument("-o", "--output", default=None, help="output EXR (default: out/<scene>.exr)")
    p.add_argument("--target-error", type=float, default=None, metavar="E",
                   help="plan variant, max_depth and spp for this relative RMSE, the total "
                        "error against a converged reference, depth bias included "
                        "(phonglab.engine.metrics; see 'phonglab plan'); --spp/--variant/--max-depth "
                        "given explicitly override the plan")
    p.add_argument("--adaptive", action="store_true",
                   help="with --target-error: adaptive sampling (docs/adaptive.md): after a "
                        "pilot, trace rays only where the estimated error exceeds its budget; "
                        "its noise target is E (no depth-bias estimate: E is the total error "
                        "of an unbiased render, phonglab.engine.metrics); writes the spp map beside "
                        "the EXR (<out>.spp.exr, <out>.spp.png)")
    p.add_argument("--max-spp", type=int, default=None, metavar="N",
                   help="with --adaptive: at most N samples in any pixel")
    p.add_argument("--by-time", action="store_true",
                   help="with --target-error: an adaptive render allocates its samples for "
                        "the least time (each pixel's cost from a probe of path lengths, "
                        "docs/adaptive.md) instead of the fewest samples")
    p.add_argument("--full-pilot", action="store_true",
                   help="with --target-error: run every step of the planner's pilot even "
                        "where the render is predicted to cost less (see 'phonglab plan')")
    add_scene_params(p)
    add_plugin(p, "mi.register_bsdf (or another mi.register_*) for the scene to use")
    p.set_defaults(func=run)


def run(args) -> int:
    from .. import registration
    from ..engine.outputs import RenderOutputs, check_output_file
    from ..engine.scenes import scene_path

    if args.max_seconds is not None:     # before the pilot, whose plans it would all refuse
        check_max_seconds(args.max_seconds)
    check_plugin_files(args.plugin, "mi.register_bsdf (or another mi.register_*)")
    path = scene_path(args.scene)
    inputs = [(path, "scene file")] + [(p, "plugin file (--plugin)") for p in args.plugin]
    out = Path(Path("out") / (path.stem + ".exr") if args.output is None else args.output)
    if args.output and (out.is_dir() or out.suffix.lower() != ".exr"):
        raise PhonglabError(f"-o {out}: the output must be a file name ending in .exr "
                            f"(e.g. -o out/{path.stem}.exr); the PNG preview is written beside it")
    if args.output is not None:      # "" and a name ending in '/' too
        check_output_file(args.output, "output image (-o)", inputs)
    RenderOutputs.beside(out).check(inputs)      # every file of the set, before any work
    from ..validate.loading import load_plugins   # lazy: Mitsuba

    with registration.plugin_files(args.plugin, load_plugins):  # in each variant it sets
        try:
            return _render(args, path, out)
        except Exception as exc:
            from ..dispatch import raised_in   # lazy: Mitsuba

            error = raised_in(exc, args.plugin)
            if error is None:
                raise
            import mitsuba as mi

            raise PhonglabError(f"the plugin raised {error} while {path.name} rendered in "
                                f"{mi.variant()}; fix the plugin (phonglab validate NAME "
                                f"--plugin FILE.py names its failing methods)"
                                + ("; a plan renders a gray scene in a mono variant: give "
                                   "--variant llvm_ad_rgb if the plugin is written for RGB only"
                                   if "mono" in (mi.variant() or "") else "")) from exc


def _render(args, path: Path, out: Path) -> int:
    """The checked render: uniform, planned (--target-error) or adaptive."""
    from ..engine.render import render_file

    if args.full_pilot and (args.target_error is None or args.adaptive):
        raise PhonglabError("--full-pilot is about the planner's pilot: use it with "
                            "--target-error E (without --adaptive), or drop it")
    if args.by_time and args.target_error is None:
        raise PhonglabError("--by-time is about adaptive sampling: use it with --target-error E "
                            "(with or without --adaptive), or drop it")
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
    """Plan for --target-error, render the plan (:func:`phonglab.planner.execute.render_plan`),
    report predicted and achieved error and time."""
    from .. import planner
    from ..engine.outputs import spp_paths
    from ..planner import execute

    # the pilot's seeds follow the render's (seed + 1, ...), so that the render, which is
    # combined with the pilot's samples, never repeats them
    plan = planner.plan(path, args.target_error, variant=args.variant,
                        max_depth=args.max_depth, spp=args.spp, seed=args.seed + planner.PILOT_SEED,
                        straight=False if args.full_pilot else None,
                        max_seconds=args.max_seconds, params=dict(args.params))
    print(plan.summary())
    done = execute.render_plan(plan, seed=args.seed, out=out, progress=True, by_time=args.by_time)
    result, error = done.result, done.error
    if plan.uses_wavefront:
        print(f"rendered {path} with {plan.model}, {plan.sampling} sampling, max_depth "
              f"{plan.max_depth} in {plan.variant}: {result.total_spp:.1f} spp on average, "
              f"{result.seconds:.3g} s (predicted {plan.chosen_seconds:.3g} s steady state)")
        if error.achieved is not None:
            print(f"  error: achieved {error.achieved:.4g} against the cached reference "
                  f"({error.reference_spp} spp); estimated {error.estimated:.4g}, "
                  f"target {plan.target_error:g}")
        else:
            print(f"  error: estimated {error.estimated:.4g} (noise {error.noise:.4g} from "
                  f"the samples, depth bias {plan.predicted_bias:.3g} from the pilot); "
                  f"target {plan.target_error:g}")
        _print_files(out, result)
        print(f"  spp map: {', '.join(str(p) for p in spp_paths(out))}")
        return 0
    times = result.pass_seconds
    # Steady state: the first pass may include JIT compilation; count it as a median pass.
    steady = statistics.median(times[1:]) * len(times) if len(times) > 1 else result.seconds
    print(f"rendered {path} with {result.metadata['spp']} spp ({plan.sampler} sampler), "
          f"max_depth {plan.max_depth} in {plan.variant}: "
          f"{result.seconds:.3g} s ({steady:.3g} s steady state; predicted "
          f"{plan.chosen_seconds:.3g} s)")
    if error.achieved is not None:
        print(f"  error: achieved {error.achieved:.4g} against the cached reference "
              f"({error.reference_spp} spp, max_depth -1); predicted "
              f"{plan.predicted_error:.4g}, target {plan.target_error:g}")
    elif error.noise is not None:
        print(f"  error: about {error.estimated:.4g} (noise {error.noise:.4g} estimated from "
              f"{len(times)} passes, depth bias {plan.predicted_bias:.3g} from the pilot; no "
              f"cached reference: make one with 'phonglab plan {path} --make-reference "
              f"4096'); predicted {plan.predicted_error:.4g}, target {plan.target_error:g}")
    else:
        print(f"  error: not measurable from one pass; predicted {plan.predicted_error:.4g}, "
              f"target {plan.target_error:g}")
    _print_files(out, result)
    return 0


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
    from ..engine import adaptive  # lazy: imports Mitsuba
    from ..engine.outputs import spp_paths
    with runtime.quiet_mitsuba():
        result = adaptive.render_file_adaptive(
            path, out, args.target_error, variant=args.variant, seed=args.seed,
            max_seconds=args.max_seconds, max_spp=args.max_spp, max_depth=args.max_depth,
            params=dict(args.params), by_time=args.by_time)
    meta = result.metadata
    why = {"target": "the estimated error meets the target",
           "max_spp": "pixels reached --max-spp", "max_seconds": "--max-seconds ran out"}
    print(f"rendered {path} adaptively in {meta['variant']}: {len(result.passes)} passes, "
          f"{result.total_spp:.1f} spp on average ({meta['spp_min']} to {meta['spp_max']}), "
          f"{result.seconds:.3g} s; estimated relative RMSE {result.estimated_error:.4g} "
          f"(target {args.target_error:g}); stopped: {why[result.stopped]}")
    _print_files(out, result)
    spp_exr, spp_png = spp_paths(out)
    print(f"  spp map: {spp_exr} (channel Y), {spp_png}")
    return 0


def _print_files(out: Path, result) -> None:
    """Where the EXR and its PNG preview are (and the preview's exposure when not 0)."""
    print(f"  EXR: {out}")
    ev = result.metadata.get("preview_exposure_ev", 0.0)
    note = f" (exposure {ev:+.1f} EV: the image exceeds 1, as graphics units do)" if ev else ""
    print(f"  PNG: {out.with_suffix('.png')}{note}")
