"""``phonglab doctor``: what phonglab found on this machine (libLLVM, variants, plugins)."""

from __future__ import annotations

import argparse


def add_parser(sub) -> None:
    p = sub.add_parser("doctor", help="show the libLLVM, variant and plugins phonglab uses",
                       description="Report the libLLVM phonglab pinned, the variants Mitsuba "
                                   "offers, and whether the plugins register.",
                       epilog="example:\n  phonglab doctor",
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.set_defaults(func=run)


def run(args) -> int:
    import mitsuba as mi

    from .. import runtime, register

    choice = runtime.configure()
    variant = register()
    # A library phonglab took as usable that Dr.Jit could not load (a file that is not
    # libLLVM): register() fell back to a scalar variant, which is what doctor must say.
    fell_back = choice.usable and not variant.startswith(("llvm", "cuda"))
    if fell_back:
        print(f"libLLVM : {choice.path} (from {choice.source}) could not be loaded by Dr.Jit "
              f"as libLLVM, so phonglab fell back to {variant} (Python plugins run about 150x "
              f"slower); point {runtime.ENV} at a libLLVM such as Debian's libLLVM-19.so, or "
              f"unset it")
    else:
        print(f"libLLVM : {choice.reason}")
    print(f"mitsuba : {mi.__version__}; variants: {', '.join(mi.variants())}")
    import drjit as dr

    extra = ""
    if variant.startswith("llvm"):
        extra = f" (Dr.Jit loaded libLLVM {'.'.join(map(str, dr.detail.llvm_version()))})"
    print(f"variant : {variant}{extra}")
    for name in ("lambert", "phong"):
        mi.load_dict({"type": name})
        print(f"plugin  : {name} loads in {variant}")
    return 0 if choice.usable and not fell_back else 1
