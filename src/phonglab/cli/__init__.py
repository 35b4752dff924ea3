"""The ``phonglab`` command line.

Each subcommand lives in its own module ``phonglab.cli.<name>`` exposing
``add_parser(subparsers)`` (which sets ``func``); :data:`SUBCOMMANDS` lists
them.  Errors meant for the user are one sentence and exit code 2; ``--debug``
shows the traceback instead.
"""

from __future__ import annotations

import argparse
import sys
import traceback

from .. import __version__, runtime
from ..errors import PhonglabError, user_errors

#: The subcommands, in the order ``--help`` lists them (module ``compare_models`` for
#: ``compare-models``).
SUBCOMMANDS = ("render", "check", "compare-models", "plan", "bench", "compare", "doctor",
               "validate", "fit")


def commands() -> tuple:
    """The subcommands' modules, in :data:`SUBCOMMANDS` order.  Imported when the parser is
    built, inside :func:`main` once SIGINT is routed to phonglab's thread
    (:func:`phonglab.runtime.interrupts_routed`): a module that starts a thread at import
    would otherwise take Ctrl-C there, and Mitsuba's render handler with it."""
    from . import (bench, check, compare, compare_models, doctor, fit, plan, render,
                   validate)
    return (render, check, compare_models, plan, bench, compare, doctor, validate, fit)

DEBUG_HELP = "show the full traceback on errors"


def _examples(parsers) -> str:
    """The ``phonglab ...`` example lines of every subcommand's epilog, for the top-level help."""
    lines = []
    for p in parsers:
        for line in (p.epilog or "").splitlines():
            if line.strip().startswith("phonglab "):
                lines.append("  " + line.strip())
    return "examples:\n" + "\n".join(lines) + \
        "\n\nRun `phonglab COMMAND --help` for a command's options and examples.\n"


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="phonglab",
        description="Lambert and modified-Phong BSDFs for Mitsuba 3, and the checks that "
                    "ground them in physics.",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--debug", action="store_true", help=DEBUG_HELP)
    parser.add_argument("--version", action="version", version=f"phonglab {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for command in commands():
        command.add_parser(sub)
    for p in sub.choices.values():
        # `phonglab render x --debug` works too; SUPPRESS keeps a top-level --debug when absent.
        if "--debug" not in p._option_string_actions:
            p.add_argument("--debug", action="store_true", default=argparse.SUPPRESS,
                           help=DEBUG_HELP)
    parser.epilog = _examples(sub.choices.values())
    return parser


def interrupted(exc: BaseException) -> bool:
    """Whether ``exc`` is a Ctrl-C, or an error a Ctrl-C caused (a C++ call that turned the
    KeyboardInterrupt raised inside it into a ``SystemError``/``RuntimeError``)."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return True
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return False


def main(argv: list[str] | None = None) -> int:
    # Ctrl-C is taken by a thread of phonglab's own, never by the C handler Mitsuba installs
    # during a render, which can hang the process (runtime.interrupts_routed); a reader that
    # closes the pipe (`| head`) ends the output, not the command (closed_stdout_tolerated).
    with runtime.interrupts_routed(), runtime.closed_stdout_tolerated():
        return _main(argv)


def _main(argv: list[str] | None) -> int:
    debug = "--debug" in (sys.argv[1:] if argv is None else argv)
    try:
        # Importing the subcommands loads Dr.Jit and Mitsuba: a Ctrl-C inside those C++
        # imports leaves them half initialised and the interpreter aborts at exit (exit -6,
        # "PyThreadState_Get: ... finalizing"), so it is held until they are loaded.
        with runtime.deferred_interrupt():
            parser = build_parser()
        args = parser.parse_args(argv)
        if not getattr(args, "func", None):
            parser.print_help()
            return 2
        debug = args.debug
        return _run(args)
    except SystemExit:                   # argparse's --help and usage errors
        raise
    except BaseException as exc:
        # A Ctrl-C first, whatever wraps it: user_errors() imports Dr.Jit, which must not
        # start after an import the interrupt broke off (it aborts the process).
        if interrupted(exc) and not debug:
            print("\nphonglab: interrupted; files already written are complete.",
                  file=sys.stderr)
            return 130
        # An OSError naming its file (a name too long, a parent that is a file, a loop of
        # symlinks, no permission) is about the path the user typed: one sentence too.
        path_error = isinstance(exc, OSError) and getattr(exc, "filename", None) is not None
        if not (isinstance(exc, user_errors()) or path_error):
            raise
        if debug:                        # the traceback added, the exit status kept
            traceback.print_exc()
        print(f"phonglab: error: {exc}", file=sys.stderr)
        return 2


def _run(args) -> int:
    """The subcommand, whose exit status is its verdict's: a ``sys.exit`` or ``os._exit`` it
    meets (a plugin's, at import or in a method: runtime.exits_intercepted) is one sentence
    naming the call and its file:line, exit 2 -- never the plugin's own status, which made a
    run that judged nothing exit 0."""
    with runtime.exits_intercepted():
        try:
            return int(args.func(args) or 0)
        except (SystemExit, runtime.PluginExited) as exc:
            from ..dispatch import exit_call    # lazy: Mitsuba

            raise PhonglabError(f"{exit_call(exc)} while 'phonglab {args.command}' ran, so "
                                f"there is no verdict; a plugin must return or raise, never "
                                f"end the process: remove the call") from exc
