"""``phonglab plan``: the leanest variant, depth and sample count for a target error, with reasons.

Lazy imports: the modules that pull in Mitsuba, matplotlib or numpy (planner, references,
scenes, metrics) are imported inside :func:`run`, because ``phonglab`` builds every subcommand's
parser at start-up and importing them there would cost every command, ``--help`` included, one
to two seconds (``python -X importtime -c 'import phonglab.engine.render'``).
"""

from __future__ import annotations

import argparse
import contextlib

from ..errors import PhonglabError
from ..parallel import add_arguments, runner_from_args
from .options import add_scene_params


def add_parser(sub) -> None:
    p = sub.add_parser(
        "plan", help="plan variant, max_depth and spp for a target relative error",
        description="Inspect a scene and a short pilot render, and print the cheapest "
                    "configuration (variant, max_depth, spp) predicted to reach a relative "
                    "RMSE, with the predicted time and the reasons. See docs/planner.md.",
        epilog="examples:\n"
               "  phonglab plan cornell_phong --target-error 0.02\n"
               "  phonglab plan gray_direct --target-error 0.01 --json\n"
               "  phonglab plan glass_slab --set res=64 --make-reference 4096\n"
               "  phonglab plan cornell_phong --make-reference 65536 --workers 2",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene", help="scene XML file, or the name of a scene phonglab ships (e.g. cornell_phong)")
    p.add_argument("--target-error", type=float, default=0.01,
                   help="relative RMSE to reach, sqrt(mean((x-r)^2/(r^2+0.01))) against a "
                        "converged reference, depth bias included (phonglab.engine.metrics; "
                        "default 0.01 = 1%%)")
    p.add_argument("--json", action="store_true", help="print the plan as JSON")
    p.add_argument("--polarized", action="store_true", help="plan a polarized variant")
    p.add_argument("--variant", default=None, help="fix the variant (the plan follows it)")
    p.add_argument("--max-depth", type=int, default=None, help="fix max_depth")
    p.add_argument("--spp", type=int, default=None, help="fix spp (the error is then predicted)")
    p.add_argument("--pilot-spp", type=int, default=None,
                   help="pilot samples per pixel, in 4 passes (default 64, fewer beyond 64x64 "
                        "pixels: the same samples per image, at least 4)")
    p.add_argument("--full-pilot", action="store_true",
                   help="run every step of the pilot (depth search, timing) even where the "
                        "render is predicted to cost less than they would (by default the "
                        "plan is then path at full depth at once, and says so)")
    add_scene_params(p)
    p.add_argument("--max-seconds", type=float, default=None, metavar="S",
                   help="refuse a plan predicted to take longer than S seconds (default: "
                        "planner.MAX_SECONDS, one hour; 'inf' allows any)")
    p.add_argument("--make-reference", type=int, default=None, metavar="SPP",
                   help="also render a converged reference (max_depth -1, SPP samples) into "
                        "the reference cache (.bench_cache/ in a checkout), which 'phonglab render --target-error' compares with")
    add_arguments(p)      # where the reference's passes render (--workers / --scheduler)
    p.set_defaults(func=run)


def run(args) -> int:
    from .. import planner
    from ..engine import metrics, references
    from ..engine.scenes import scene_path

    if args.make_reference is not None and args.make_reference < 16:
        raise PhonglabError(f"--make-reference needs at least 16 spp (16 passes), got "
                            f"{args.make_reference}.")
    if args.pilot_spp is not None and args.pilot_spp < 8:
        raise PhonglabError(f"--pilot-spp must be at least 8 (8 passes), got {args.pilot_spp}.")
    # every value checked here, before the pilot (whose plans a bad limit would all refuse)
    options = planner.PlanOptions(args.target_error, polarized=args.polarized,
                                  variant=args.variant, max_depth=args.max_depth, spp=args.spp,
                                  params=dict(args.params), max_seconds=args.max_seconds,
                                  straight=False if args.full_pilot else None,
                                  pilot_spp=args.pilot_spp)
    path = scene_path(args.scene)
    params = options.params
    # A missing reference's passes run on --workers/--scheduler: reached before the pilot.
    runner = runner_from_args(args)
    rendering = (args.make_reference is not None and
                 references.cached(path, params, min_spp=args.make_reference) is None)
    if rendering:       # where it will be cached, before the pilot
        from ..engine.outputs import check_output_folder
        check_output_folder(references.CACHE_DIR / "references", "reference cache")
    with runner if rendering else contextlib.nullcontext():
        p = planner.plan(path, options)
        print(p.to_json() if args.json else p.summary())
        if args.make_reference is not None:
            ref = references.reference(path, args.make_reference, params=params, progress=True,
                                       runner=runner)
            if not args.json:
                print(f"reference: {ref.spp} spp, max_depth -1, {ref.metadata['variant']}, "
                      f"relative noise {metrics.relative_noise(ref.image, ref.stderr):.3g}, "
                      f"cached in {ref.path}")
    return 0
