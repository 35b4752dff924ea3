"""``phonglab fit``: the best modified Phong (or Lambert) for a target BSDF, by Dr.Jit AD."""

from __future__ import annotations

import argparse

from ..errors import PhonglabError
from ..settings import parse_sets
from .options import add_plugin, add_timeout, check_plugin_files, check_timeout, load_plugin_files


def add_parser(sub) -> None:
    p = sub.add_parser(
        "fit", help="fit phong (k_d, k_s, p) to a physically based BSDF with Dr.Jit AD",
        description="Fit the modified Phong BSDF (k_d/π + k_s (p+2)/(2π) cos^p α, k_d + k_s <= 1) "
                    "or Lambert to any registered BSDF by minimizing the relative L2 distance of "
                    "f cos θ_i cos θ_o (luminance) over both hemispheres, with gradients from "
                    "Dr.Jit's AD through the phong plugin and L-BFGS-B. Prints the fitted "
                    "parameters, the residual (overall, per incidence angle, worst direction) "
                    "and the albedo of fit and target against θ_i. See docs/fitting.md.",
        epilog="examples:\n  phonglab fit roughconductor --set alpha=0.2\n"
               "  phonglab fit roughplastic --set alpha=0.1 --set distribution=ggx --json out/fit.json\n"
               "  phonglab fit mybsdf --plugin mybsdf.py",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("target", help="a registered BSDF plugin: roughconductor, roughplastic, "
                                  "principled, plastic, phong, ...")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", dest="settings",
                   help="a parameter of the target (repeatable): a number, true/false, 'r, g, b', "
                        "a string or nested (bsdf.type=...), e.g. --set alpha=0.2 "
                        "--set distribution=ggx (grammar: phonglab.settings)")
    add_plugin(p, "mi.register_bsdf")
    p.add_argument("--model", choices=["phong", "lambert"], default="phong",
                   help="the classic model to fit (default phong)")
    p.add_argument("--maxiter", type=int, default=200, help="L-BFGS-B iterations at most (default 200)")
    p.add_argument("--variant", default=None, help="Mitsuba variant (default: llvm_ad_rgb)")
    p.add_argument("--json", default=None, metavar="PATH", help="write the result as JSON")
    p.add_argument("--report", default=None, metavar="PATH", help="write the printed report to a file")
    add_timeout(p, "fit")
    p.set_defaults(func=run)


def run(args) -> int:
    params = parse_sets(args.settings)
    if args.maxiter < 1:
        raise PhonglabError(f"--maxiter must be at least 1, got {args.maxiter}")
    check_timeout(args.timeout)
    # Imported here: outputs loads numpy and OpenEXR, which `phonglab --help` does not need.
    from ..engine.outputs import check_output_files, write_json, write_text

    check_plugin_files(args.plugin, "mi.register_bsdf")
    check_output_files([(args.json, "JSON file (--json)"), (args.report, "report (--report)")],
                       [(path, "plugin file (--plugin)") for path in args.plugin])
    # Imported here, not at the top: they load Mitsuba and scipy, which `phonglab --help` does not need.
    from .. import dispatch, registration, runtime
    from ..fit.optimize import fit, format_result
    from ..validate.timeout import TopicTimeout, topic_timeout, within_topic_limit

    variant = args.variant or runtime.default_variant()
    runtime.check_variant(variant)
    if not variant.endswith(("_ad_rgb", "_ad_mono")):
        raise PhonglabError(f"fitting needs gradients and RGB or mono colour: use an *_ad_rgb or "
                            f"*_ad_mono variant such as llvm_ad_rgb, not {variant}")
    registration.register(variant)
    with topic_timeout(args.timeout):
        load_plugin_files(args.plugin)
        try:
            with within_topic_limit():
                result = fit(args.target, params, model=args.model, maxiter=args.maxiter)
        except TopicTimeout:
            raise PhonglabError(f"the fit of {args.target!r} did not finish within "
                                f"{args.timeout:g} s (stopped by --timeout: does the plugin's "
                                f"Python code loop forever?); raise --timeout or fix the "
                                f"plugin") from None
        except Exception as exc:
            error = dispatch.raised_in(exc, args.plugin)
            if error is None:
                raise                         # not from a --plugin file: as it was
            raise PhonglabError(f"the BSDF {args.target!r} raised {error} "
                                f"while it was fitted, so there is no fit; fix the plugin "
                                f"(phonglab validate {args.target} --plugin FILE.py shows "
                                f"which methods fail)") from exc
    text = format_result(result)
    # Files first: a closed stdout (`| head`) must not lose them.
    if args.report is not None:
        write_text(args.report, text + "\n")
    if args.json is not None:
        write_json(args.json, result.as_dict(), indent=1, end="\n")
    print(text)
    return 0
