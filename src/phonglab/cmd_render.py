"""``phonglab render``: render a scene to a float EXR with provenance and a PNG preview."""

from __future__ import annotations

import argparse
from pathlib import Path


def add_parser(sub) -> None:
    p = sub.add_parser(
        "render", help="render a scene to EXR + PNG",
        description="Render a Mitsuba XML scene (phonglab's plugins registered) to a float "
                    "OpenEXR file with its provenance in the header, and a PNG preview.",
        epilog="example:\n  phonglab render scenes_xml/cornell_phong.xml --spp 128 -o out/cornell.exr",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene", help="scene XML file, or a name from scenes_xml/ (e.g. cornell_phong)")
    p.add_argument("--spp", type=int, default=None, help="samples per pixel (default: the scene's)")
    p.add_argument("--variant", default=None, help="Mitsuba variant (default: llvm_ad_rgb)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--max-depth", type=int, default=None, help="path length limit (default: the scene's)")
    p.add_argument("-o", "--output", default=None, help="output EXR (default: out/<scene>.exr)")
    p.set_defaults(func=run)


def run(args) -> int:
    from .render import render_file, scene_path

    path = scene_path(args.scene)
    out = Path(args.output or Path("out") / (path.stem + ".exr"))
    if out.is_dir() or out.suffix.lower() != ".exr":
        from .render import PhonglabError

        raise PhonglabError(f"-o {out}: the output must be a file name ending in .exr "
                            f"(e.g. -o out/{path.stem}.exr); the PNG preview is written beside it")
    result = render_file(path, out, spp=args.spp, variant=args.variant, seed=args.seed,
                         max_depth=args.max_depth)
    meta = result.metadata
    print(f"rendered {path} with {meta['spp']} spp in {meta['variant']} "
          f"({result.seconds:.2f} s, first pass {result.pass_seconds[0]:.2f} s incl. JIT)")
    print(f"  EXR: {out}")
    print(f"  PNG: {out.with_suffix('.png')}")
    return 0
