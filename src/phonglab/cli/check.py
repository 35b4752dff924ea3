"""``phonglab check``: run the physics checks and print what holds, by how much, with what error.

Exit status: 0 when every row passes (rows marked KNOWN, documented discrepancies outside
phonglab, do not count), 1 when a row fails, 2 on bad input.
"""

from __future__ import annotations

import argparse
import platform
import sys
import time

import mitsuba as mi

from .. import __version__, checks, register
from ..errors import PhonglabError
from ..settings import mitsuba_reason
from ..engine.outputs import check_output_file, check_output_folder, write_json
from ..verdict import Report, format_number
from .options import (add_plugin, add_seed, add_timeout, check_plugin_files, check_timeout,
                      load_plugin_files)

#: Where difference images of a failing scene check go unless --out-dir says (made only then).
DEFAULT_OUT_DIR = "out/checks"


def add_parser(sub) -> None:
    p = sub.add_parser(
        "check", help="prove the plugins against physics and Mitsuba's built-ins (table)",
        description="Run phonglab's physics checks (white furnace, reflection equation, "
                    "lambert vs diffuse, radiance constancy, Snell, plugin sanity) and print "
                    "one row per comparison: measured, expected (and its source), standard "
                    "error, tolerance, verdict. Exits 1 if any row fails.",
        epilog="examples:\n  phonglab check\n  phonglab check --only snell --only sanity\n"
               "  phonglab check --spp 256 --json out/checks.json\n"
               "  phonglab check --lambert mylambert --plugin mylambert.py --only sanity",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--only", action="append", metavar="NAME", choices=checks.CHECK_NAMES,
                   help=f"run only this check (repeatable): {', '.join(checks.CHECK_NAMES)}")
    p.add_argument("--json", metavar="PATH", help="also write the rows as JSON to PATH")
    p.add_argument("--spp", type=int, default=256,
                   help="samples per pixel of the statistical renders (default 256; BSDF-level "
                        "estimates use 1024x this many directions, chi-square 4096x)")
    add_seed(p)
    p.add_argument("--out-dir", default=None,
                   help=f"where difference images of a failing scene check go (default "
                        f"{DEFAULT_OUT_DIR})")
    p.add_argument("--lambert", default="lambert", metavar="PLUGIN",
                   help="registered BSDF checked as the Lambertian (default lambert)")
    p.add_argument("--phong", default="phong", metavar="PLUGIN",
                   help="registered BSDF checked as the modified Phong (default phong)")
    add_plugin(p, "mi.register_bsdf")
    p.add_argument("--details", action="store_true",
                   help="print what each row compares, its source and details")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_timeout(p, "check")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..validate.timeout import topic_timeout

    check_timeout(args.timeout)
    # Config refuses a bad --spp: built first, before the plugins load; the outputs next.
    check_plugin_files(args.plugin, "mi.register_bsdf")
    if args.json is not None:
        check_output_file(args.json, "JSON file (--json)",
                          [(path, "plugin file (--plugin)") for path in args.plugin])
    if args.out_dir is not None:
        check_output_folder(args.out_dir, "folder of difference images (--out-dir)")
    cfg = checks.Config(spp=args.spp, seed=args.seed, out_dir=args.out_dir or DEFAULT_OUT_DIR,
                        lambert=args.lambert, phong=args.phong)
    names = args.only or list(checks.CHECK_NAMES)
    with topic_timeout(args.timeout):       # the plugin files' loading and each check
        _require_plugins(args.lambert, args.phong, plugins=args.plugin)
        return _run(args, cfg, names)


def _run(args, cfg, names) -> int:
    """The checks, the table, the summary and the JSON."""
    # Lazy: scipy (through phonglab.stats) and tqdm would add ~0.6 s to every `phonglab` start.
    from tqdm import tqdm

    from .. import stats

    bar = None
    if not args.no_progress:
        bar = tqdm(total=len(names), unit="check", leave=False, file=sys.stderr)
        cfg.progress = bar.set_description
    t0 = time.perf_counter()
    done: list[str] = []

    def on_check(name: str) -> None:
        if bar is not None:
            if done:
                bar.update(1)
            bar.set_description(name)
        done.append(name)

    try:
        results = checks.run_checks(names, cfg, on_check=on_check)
    finally:
        if bar is not None:
            bar.update(1)
            bar.close()
    seconds = time.perf_counter() - t0
    report = Report({
        "phonglab_version": __version__, "mitsuba_version": mi.__version__,
        "variant": mi.variant(), "spp": cfg.spp, "seed": cfg.seed,
        "samples": cfg.samples, "chi2_samples": cfg.chi2_samples, "alpha": stats.ALPHA,
        "seconds": round(seconds, 2), "checks": names, "python": platform.python_version()},
        results)
    print(report.table(digits=6, stderr=True, reasons=False))
    if args.details:
        print()
        for r in results:
            print(f"[{r.topic}] {r.name}: {r.reason}; expected from: {r.details.get('source')}"
                  + (f"; known issue: {_issue(r)}" if r.status == "KNOWN" else ""))
    _summary(report, seconds, cfg)
    if args.json is not None:
        print(f"JSON: {write_json(args.json, report.to_dict())}")
    return 0 if report.passed else 1


def _summary(report: Report, seconds: float, cfg) -> None:
    """The counts, then each documented discrepancy and each failing row on a line."""
    rows = report.rows
    known = [r for r in rows if r.status == "KNOWN"]
    print(f"\n{len(rows)} rows: {sum(r.status == 'pass' for r in rows)} pass, {len(known)} known "
          f"discrepancies (documented in docs/checks.md), {len(report.failing)} fail "
          f"({seconds:.1f} s, spp {cfg.spp}, seed {cfg.seed}).")
    for issue in dict.fromkeys(_issue(r) for r in known):
        which = ", ".join(f"{r.topic}/{r.name}" for r in known if _issue(r) == issue)
        print(f"  KNOWN {which}: {issue}")
    for r in report.failing:
        if r.measured is None:          # nothing measured: the plugin raised, exited, hung
            print(f"  fail {r.topic}/{r.name}: {r.reason}")
            continue
        print(f"  fail {r.topic}/{r.name}: measured {format_number(r.measured, 6)}, expected "
              f"{format_number(r.expected, 6)} ± {format_number(r.tolerance, 3)} "
              f"({r.details.get('source')})"
              + (f"; difference image {r.details['difference_image']}"
                 if "difference_image" in r.details else ""))


def _issue(row) -> str:
    """The documented cause of a KNOWN row."""
    return row.details.get("known_issue", row.reason)


#: What ``check`` sets on the plugins it checks: (flag, model, the spec of a name, its words).
ROLES = (("--lambert", "Lambertian", lambda name: checks.gray(name, reflectance=0.7),
          "reflectance (an RGB texture)"),
         ("--phong", "modified Phong", lambda name: checks.phong_dict(name, 0.4, 0.5, 30.0),
          "diffuse_reflectance and specular_reflectance (RGB textures) and exponent (a float)"))


def _require_plugins(*names: str, plugins=()) -> None:
    """A clear error when a plugin named by --lambert/--phong is not registered (after the
    ``--plugin`` files ran once), is not a BSDF, or does not take the parameters ``check``
    sets on it (:data:`ROLES`): one sentence before any check runs."""
    register()
    registered = load_plugin_files(plugins)
    for name, (flag, model, spec, sets) in zip(names, ROLES):
        words = [word for word, n in registered if n == name]
        builtin = mi.PluginManager.instance().plugin_type(name)
        if words and "BSDF" not in words or builtin not in (mi.ObjectType.BSDF,
                                                             mi.ObjectType.Unknown):
            what = (f"{'an' if words[0][0] in 'aeiou' else 'a'} {words[0]} (registered by the "
                    f"plugin file)" if words else
                    f"a Mitsuba {str(builtin).split('.')[-1]} plugin")
            raise PhonglabError(f"{flag} {name!r} is {what}, not a BSDF; {flag} names the BSDF "
                                f"check judges as the {model} (a file that calls "
                                f"mi.register_bsdf), or drop {flag}")
        try:
            mi.load_dict({"type": name})
        except Exception as exc:
            if "not found" in str(exc) or "unknown" in str(exc).lower():
                mine = [n for word, n in registered if word == "BSDF"]
                raise PhonglabError(f"no BSDF plugin named {name!r} is registered; "
                                    + (f"the plugin files registered {', '.join(map(repr, mine))}"
                                       if mine else "give --plugin FILE.py, a file that calls "
                                       f"mi.register_bsdf({name!r}, ...)")
                                    + ", or drop the option") from None
            raise
        try:
            plugin = mi.load_dict(spec(name))
        except Exception as exc:
            raise PhonglabError(f"check sets {sets} on the BSDF it judges as the {model} "
                                f"({flag} {name!r}), and loading {name!r} with them fails: "
                                f"{mitsuba_reason(exc)}; give {flag} a BSDF that takes those "
                                f"parameters, or drop {flag}") from None
        if not isinstance(plugin, mi.BSDF):
            raise PhonglabError(f"{flag} {name!r} is a {type(plugin).__name__}, not a BSDF; "
                                f"{flag} names the BSDF check judges as the {model}, or drop "
                                f"{flag}")
