"""``phonglab compare``: RMSE, relative MSE and the mean difference (with its standard error)
of two EXR images, and a difference image."""

from __future__ import annotations

import argparse
import json
from pathlib import Path


def add_parser(sub) -> None:
    p = sub.add_parser(
        "compare", help="compare two EXR images (RMSE, relMSE, mean difference ± s.e.)",
        description="Compare image A with reference B: RMSE, relative MSE "
                    "mean((A-B)^2/(B^2+eps)), and the mean difference A-B with its standard "
                    "error, taken from the .stderr.exr files `phonglab render` writes beside "
                    "its output when both exist, else from the spread of the pixel "
                    "differences. Optionally writes a difference image (red: A brighter).",
        epilog="examples:\n"
               "  phonglab compare out/a.exr out/b.exr --diff out/a_minus_b.png\n"
               "  phonglab compare a.exr ref.exr --stderr-a a.stderr.exr --stderr-b ref.stderr.exr",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("a", metavar="A.exr", help="image under test")
    p.add_argument("b", metavar="B.exr", help="reference image")
    p.add_argument("--diff", metavar="OUT.png", default=None,
                   help="write the signed difference A-B as a PNG (diverging colormap)")
    p.add_argument("--stderr-a", metavar="FILE.exr", default=None,
                   help="per-pixel standard error of A (default: A.stderr.exr when it and "
                        "B.stderr.exr exist)")
    p.add_argument("--stderr-b", metavar="FILE.exr", default=None,
                   help="per-pixel standard error of B (give both or neither)")
    p.add_argument("--no-stderr-files", action="store_true",
                   help="ignore .stderr.exr files; use the spread of the pixel differences")
    p.add_argument("--eps", type=float, default=None,
                   help="epsilon of the relative MSE (default 1e-2)")
    p.add_argument("--json", action="store_true", help="print the numbers as JSON")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..engine import compare
    from ..engine.metrics import REL_EPS
    from ..errors import PhonglabError
    from ..engine.outputs import check_output_file

    if args.eps is not None and not args.eps > 0:
        raise PhonglabError(f"--eps must be > 0 (it keeps dark pixels from dominating the "
                            f"relative MSE), got {args.eps}")
    if args.diff and Path(args.diff).suffix.lower() != ".png":
        raise PhonglabError(f"--diff writes a PNG image, but {args.diff} does not end in .png; "
                            f"give a path like out/a_minus_b.png")
    if args.diff is not None:      # the output rules of every command, before any work
        check_output_file(args.diff, "difference image (--diff)",
                          [(args.a, "image A"), (args.b, "image B"),
                           (args.stderr_a, "standard error of A (--stderr-a)"),
                           (args.stderr_b, "standard error of B (--stderr-b)")])
    result, img_a, img_b, meta_a, meta_b = compare.compare_files(
        args.a, args.b, args.stderr_a, args.stderr_b, auto_stderr=not args.no_stderr_files,
        eps=args.eps if args.eps is not None else REL_EPS)
    if args.json:
        print(json.dumps(result.as_dict(), indent=2, allow_nan=False))
    else:
        print(f"A: {args.a}: {compare.describe_metadata(meta_a)}")
        print(f"B: {args.b}: {compare.describe_metadata(meta_b)}")
        print(result.summary())
        for key, what in (("scene_sha256", "scene files"), ("variant", "variants")):
            if meta_a.get(key) is not None and meta_b.get(key) is not None \
                    and meta_a[key] != meta_b[key]:
                print(f"note: A and B were rendered from different {what} ({key} differs): "
                      f"their difference is not only noise")
    if args.diff is not None:
        compare.write_diff_png(args.diff, img_a, img_b,
                               title=f"A − B: RMSE {result.rmse:.3g}, mean {result.mean_diff:+.3g}"
                                     f" ± {result.mean_diff_stderr:.2g}")
        if not args.json:
            print(f"difference image: {args.diff}")
    return 0
