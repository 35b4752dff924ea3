"""``phonglab compare-models``: the seed's graphics model versus radiance units versus path tracing."""

from __future__ import annotations

import argparse
from pathlib import Path

from .options import add_scene_params, add_seed


def add_parser(sub) -> None:
    p = sub.add_parser(
        "compare-models", help="render a scene with whitted (graphics, radiance) and path; diff them",
        description="Render a scene three ways with the same materials and lights: the seed's "
                    "classic formula (whitted, graphics units), the same direct light in radiance "
                    "units (whitted, radiance), and Mitsuba's path tracer. Writes the three "
                    "images (EXR + PNG), difference images (diverging colour map), figure.png and "
                    "table.txt, and prints where and by how much they differ.",
        epilog="examples:\n  phonglab compare-models exponent_series --spp 16 -o out/exponent_series\n"
               "  phonglab compare-models attenuation_demo -D c=1 -D a=0",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene", help="scene XML file, or the name of a scene phonglab ships (e.g. exponent_series)")
    p.add_argument("--spp", type=int, default=16,
                   help="samples per pixel of the whitted renders (default 16)")
    p.add_argument("--path-spp", type=int, default=None,
                   help="samples per pixel of the path tracer (default 8 x --spp)")
    p.add_argument("--max-depth", type=int, default=None,
                   help="path length for all three (default: the scene's, else 5)")
    add_seed(p)
    p.add_argument("--variant", default=None, help="Mitsuba variant (default: llvm_ad_rgb)")
    add_scene_params(p, "-D", "--param", "--set")
    p.add_argument("-o", "--output", default=None,
                   help="output folder (default: out/compare_<scene>)")
    p.set_defaults(func=run)


def run(args) -> int:
    # Imported here, not at the top: `phonglab` imports every subcommand module to build its
    # parser, and these pull in Mitsuba and matplotlib, which `phonglab --help` does not need.
    from ..engine.compare_models import compare_models, format_table
    from ..engine.outputs import check_output_folder
    from ..engine.scenes import scene_path

    params = dict(args.params)
    path = scene_path(args.scene)
    out = check_output_folder(Path("out") / f"compare_{path.stem}" if args.output is None
                              else args.output, "output folder (-o)")
    result = compare_models(path, out, spp=args.spp, path_spp=args.path_spp, seed=args.seed,
                            max_depth=args.max_depth, variant=args.variant, progress=True,
                            params=params)
    depth = result.integrators["path"]["max_depth"]
    print(f"compared {path} (max_depth {depth}): "
          + ", ".join(f"{k} {v:.2f} s" for k, v in result.seconds.items()))
    print(format_table(result.stats))
    print(f"  files: {out}/ (graphics|radiance|path .exr/.png, diff_*.png, figure.png, table.txt)")
    return 0
