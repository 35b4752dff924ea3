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
    print(f"libLLVM : {choice.reason}")
    print(f"mitsuba : {mi.__version__}; variants: {', '.join(mi.variants())}")
    variant = register()
    import drjit as dr

    extra = ""
    if variant.startswith("llvm"):
        extra = f" (Dr.Jit loaded libLLVM {'.'.join(map(str, dr.detail.llvm_version()))})"
    print(f"variant : {variant}{extra}")
    for name in ("lambert", "phong"):
        mi.load_dict({"type": name})
        print(f"plugin  : {name} loads in {variant}")
    return 0 if choice.usable else 1
