"""``phonglab render``: render a scene to a float EXR with provenance and a PNG preview.

Three renders, one per set of flags (:func:`request`, the one place the flags are checked,
before any work): uniform (``--spp``), planned (``--target-error E``: the planner's total error,
depth bias included) and adaptive (``--adaptive --target-noise N``: a noise target, no depth
bias estimated).  The planner and the engine say what each did; this module parses and prints.

Lazy imports: the modules that pull in Mitsuba, matplotlib or numpy (render, scenes, planner,
adaptive) are imported inside :func:`run`, :func:`request`, :func:`run_planned` and
:func:`run_adaptive`, because ``phonglab`` builds every subcommand's parser at start-up and
importing them there would cost every command, ``--help`` included, one to two seconds
(``python -X importtime -c 'import phonglab.engine.render'``).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from .. import runtime
from ..errors import PhonglabError
from .options import add_plugin, add_scene_params, add_seed, check_plugin_files


def add_parser(sub) -> None:
    p = sub.add_parser(
        "render", help="render a scene to EXR + PNG",
        description="Render a Mitsuba XML scene (phonglab's plugins registered) to a float "
                    "OpenEXR file with its provenance in the header, and a PNG preview.",
        epilog="examples:\n  phonglab render cornell_phong --spp 128 -o out/cornell.exr\n"
               "  phonglab render cornell_phong --target-error 0.02   (planned: see 'phonglab plan')\n"
               "  phonglab render gray_direct --adaptive --target-noise 0.01 --stop-after 60\n"
               "  phonglab render myscene.xml --plugin mybsdf.py   (a scene with your own BSDF)",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene", help="scene XML file, or the name of a scene phonglab ships (e.g. cornell_phong)")
    p.add_argument("--spp", type=int, default=None, help="samples per pixel (default: the scene's)")
    p.add_argument("--variant", default=None, help="Mitsuba variant (default: llvm_ad_rgb)")
    add_seed(p)
    p.add_argument("--max-depth", type=int, default=None, help="path length limit (default: the scene's)")
    p.add_argument("-o", "--output", default=None, help="output EXR (default: out/<scene>.exr)")
    p.add_argument("--target-error", type=float, default=None, metavar="E",
                   help="plan variant, max_depth and spp for this relative RMSE, the total "
                        "error against a converged reference, depth bias included "
                        "(phonglab.engine.metrics; see 'phonglab plan'); --spp/--variant/--max-depth "
                        "given explicitly override the plan")
    p.add_argument("--max-seconds", type=float, default=None, metavar="S",
                   help="with --target-error: refuse a plan predicted to take longer than S "
                        "seconds (default: planner.MAX_SECONDS, one hour; 'inf' allows any)")
    p.add_argument("--full-pilot", action="store_true",
                   help="with --target-error: run every step of the planner's pilot even "
                        "where the render is predicted to cost less (see 'phonglab plan')")
    p.add_argument("--adaptive", action="store_true",
                   help="adaptive sampling to --target-noise N (docs/adaptive.md): after a "
                        "pilot, trace rays only where the estimated error exceeds its budget; "
                        "writes the spp map beside the EXR (<out>.spp.exr, <out>.spp.png)")
    p.add_argument("--target-noise", type=float, default=None, metavar="N",
                   help="with --adaptive: the relative RMSE the render's own noise may leave "
                        "(no depth-bias estimate: N is the total error of an unbiased render "
                        "only, phonglab.engine.metrics; --target-error E plans for a total error)")
    p.add_argument("--max-spp", type=int, default=None, metavar="N",
                   help="with --adaptive: at most N samples in any pixel")
    p.add_argument("--stop-after", type=float, default=None, metavar="S",
                   help="with --adaptive: stop adding passes after S seconds of rendering")
    p.add_argument("--by-time", action="store_true",
                   help="with --target-error or --adaptive: an adaptive render allocates its "
                        "samples for the least time (each pixel's cost from a probe of path "
                        "lengths, docs/adaptive.md) instead of the fewest samples")
    add_scene_params(p)
    add_plugin(p, "mi.register_bsdf (or another mi.register_*) for the scene to use")
    p.set_defaults(func=run)


def request(args):
    """The render the flags ask for, every flag and combination checked here before any work
    (one sentence each): None (uniform), the planner's options (``--target-error E``:
    :class:`phonglab.planner.PlanOptions`, which checks its values) or adaptive sampling
    (``--adaptive --target-noise N``: :class:`phonglab.engine.adaptive.AdaptiveSampling`,
    likewise)."""
    if args.adaptive:
        if args.target_error is not None:
            raise PhonglabError("--target-error is the total error the planner aims at, depth "
                                "bias included; adaptive sampling aims at a noise: give "
                                "--adaptive --target-noise N, or drop --adaptive (the planner "
                                "prices adaptive sampling itself)")
        if args.target_noise is None:
            raise PhonglabError("--adaptive needs --target-noise N, the relative noise to "
                                "reach (e.g. --target-noise 0.02)")
        if args.spp is not None:
            raise PhonglabError("--adaptive chooses the samples per pixel itself; drop --spp "
                                "(cap them with --max-spp N)")
        if args.max_seconds is not None:
            raise PhonglabError("--max-seconds refuses a plan (--target-error E) predicted to "
                                "take longer; adaptive sampling stops after S seconds with "
                                "--stop-after S")
        if args.full_pilot:
            raise PhonglabError("--full-pilot is about the planner's pilot: use it with "
                                "--target-error E (without --adaptive), or drop it")
        from ..engine.adaptive import AdaptiveSampling  # lazy: imports Mitsuba

        return AdaptiveSampling(args.target_noise, args.stop_after, args.max_spp,
                                by_time=args.by_time)
    for flag, value in (("--target-noise", args.target_noise), ("--max-spp", args.max_spp),
                        ("--stop-after", args.stop_after)):
        if value is not None:
            raise PhonglabError(f"{flag} applies to adaptive sampling; add --adaptive"
                                f"{'' if flag == '--target-noise' else ' --target-noise N'} "
                                f"(or use --spp for a uniform render, --target-error E for a "
                                f"planned one)")
    if args.target_error is None:
        for flag, given, about, use in (
                ("--max-seconds", args.max_seconds is not None, "a plan's predicted time",
                 "--target-error E"),
                ("--full-pilot", args.full_pilot, "the planner's pilot", "--target-error E"),
                ("--by-time", args.by_time, "adaptive sampling",
                 "--target-error E or --adaptive --target-noise N")):
            if given:
                raise PhonglabError(f"{flag} is about {about}: use it with {use}, or drop it")
        return None
    from .. import planner  # lazy: imports Mitsuba

    return planner.PlanOptions(args.target_error, variant=args.variant,
                               max_depth=args.max_depth, spp=args.spp,
                               params=dict(args.params), max_seconds=args.max_seconds,
                               straight=False if args.full_pilot else None, seed=args.seed)


def run(args) -> int:
    from .. import registration
    from ..engine.outputs import RenderOutputs, check_output_file
    from ..engine.scenes import scene_path

    how = request(args)
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
            return _render(args, how, path, out)
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


def _render(args, how, path: Path, out: Path) -> int:
    """The checked render (``how``, :func:`request`): uniform, planned or adaptive."""
    from ..engine.render import render_file

    if args.target_error is not None:
        return run_planned(args, how, path, out)
    if args.adaptive:
        return run_adaptive(args, how, path, out)
    result = render_file(path, out, spp=args.spp, variant=args.variant, seed=args.seed,
                         max_depth=args.max_depth, params=dict(args.params))
    meta = result.metadata
    print(f"rendered {path} with {meta['spp']} spp in {meta['variant']} "
          f"({result.seconds:.2f} s, first pass {result.pass_seconds[0]:.2f} s incl. JIT)")
    _print_files(out, result)
    return 0


def run_planned(args, options, path: Path, out: Path) -> int:
    """Plan for --target-error (``options``), render the plan
    (:func:`phonglab.planner.execute.render_plan`, with the seed it was planned for), and print
    the plan and what its render did."""
    from .. import planner
    from ..planner import execute

    plan = planner.plan(path, options)
    print(plan.summary())
    done = execute.render_plan(plan, out=out, progress=True, by_time=args.by_time)
    print(done.describe())
    _print_files(out, done.result)
    return 0


def run_adaptive(args, sampling, path: Path, out: Path) -> int:
    """--adaptive --target-noise N: adaptive sampling (``sampling``), the spp map beside the
    image."""
    from ..engine.render import render_scene_file

    with runtime.quiet_mitsuba():
        result = render_scene_file(path, out, sampling, variant=args.variant, seed=args.seed,
                                   max_depth=args.max_depth, params=dict(args.params))
    print(result.describe(path))
    _print_files(out, result)
    return 0


def _print_files(out: Path, result) -> None:
    """Where the EXR and its PNG preview are (and the preview's exposure when not 0), and the
    spp map of an adaptively sampled render (its header says ``adaptive``)."""
    from ..engine.outputs import spp_paths

    print(f"  EXR: {out}")
    ev = result.metadata.get("preview_exposure_ev", 0.0)
    note = f" (exposure {ev:+.1f} EV: the image exceeds 1, as graphics units do)" if ev else ""
    print(f"  PNG: {out.with_suffix('.png')}{note}")
    if result.metadata.get("adaptive"):
        spp_exr, spp_png = spp_paths(out)
        print(f"  spp map: {spp_exr} (channel Y), {spp_png}")
