"""``phonglab validate``: physics conformance of one BSDF (or every built-in), one emitter or one
integrator, as a table.

The kind is detected: the BSDF path runs first, unchanged; a spec that does not load as a BSDF
and names an emitter (:func:`phonglab.validate.emitter.kind.is_emitter`) is validated on the
emitter topics, one that names an integrator
(:func:`phonglab.validate.integrator.kind.is_integrator`) on the integrator topics.

Exit status: 0 when every row passes (KNOWN rows, with a documented cause, allowed), 1 when a
row fails, 2 on bad input (unknown plugin type, bad --set, missing file, unknown topic): one
sentence, checked before any expensive work.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ..parallel import add_arguments, runner_from_args
from ..settings import parse_sets
from ..validate.bsdf.topics import TOPICS
from ..validate.emitter.topics import TOPICS as EMITTER_TOPICS
from ..validate.integrator.topics import TOPICS as INTEGRATOR_TOPICS
from ..validate.inputs import ValidateError, check_topics
from ..verdict import Report
from .options import add_seed

EPILOG = """examples:
  phonglab validate diffuse
  phonglab validate roughconductor          # Mitsuba's documented findings are KNOWN rows
  phonglab validate roughplastic --set alpha=0.25 --set distribution=ggx --quick
  phonglab validate mybsdf --plugin mybsdf.py --report out/mybsdf.html
  phonglab validate twosided --set nested.type=diffuse --set nested.reflectance=0.3,0.4,0.5
  phonglab validate point --quick
  phonglab validate area --set shape.type=sphere --set shape.flip_normals=true
  phonglab validate mylight --plugin mylight.py
  phonglab validate path --quick
  phonglab validate myint --plugin myint.py --json out/myint.json
  phonglab validate --all-builtins --quick --json out/conformance.json
  phonglab validate --all-builtins --scheduler tcp://10.0.0.5:8786 --json out/conformance.json
"""


def add_parser(sub) -> None:
    p = sub.add_parser(
        "validate", help="check any Mitsuba BSDF: finiteness, weights, pdf, chi2, energy, "
                         "reciprocity, components, gradients, cost",
        description="Validate a Mitsuba 3 BSDF (a registered plugin type, a Python plugin "
                    "registered by --plugin, or an XML file holding one <bsdf>) on every "
                    f"topic ({', '.join(TOPICS)}) and print one row per check. "
                    "An emitter (a name, dict or XML that loads as one, or a --plugin file "
                    "calling mi.register_emitter) is detected and validated on the emitter "
                    f"topics ({', '.join(EMITTER_TOPICS)}); --set shape.type=sphere attaches an "
                    "area emitter to a shape. An integrator (path, direct, ptracer, prb, ... or a "
                    "--plugin file calling mi.register_integrator) on the integrator topics "
                    f"({', '.join(INTEGRATOR_TOPICS)}). "
                    "Exits 0 when all pass, 1 when a row fails, 2 on bad input.",
        epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("bsdf", nargs="?", metavar="BSDF",
                   help="plugin type name (diffuse, roughplastic, lambert, ...; an emitter: "
                        "point, area, constant, ...; an integrator: path, direct, ...) or an XML "
                        "file")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="a parameter: float, RGB 'r,g,b', string, or nested (nested.type=diffuse)")
    p.add_argument("--plugin", action="append", default=[], metavar="FILE.py",
                   help="a Python file run after the variant is set; it calls mi.register_bsdf "
                        "(or mi.register_emitter, mi.register_integrator)")
    p.add_argument("--variant", help="Mitsuba variant (default llvm_ad_rgb)")
    p.add_argument("--only", action="append", metavar="TOPIC",
                   help=f"run only this topic (repeatable): {', '.join(TOPICS)}; an emitter's: "
                        f"{', '.join(EMITTER_TOPICS)}; an integrator's: "
                        f"{', '.join(INTEGRATOR_TOPICS)}")
    p.add_argument("--json", metavar="PATH", help="write the report as JSON")
    p.add_argument("--report", metavar="PATH.html", help="write a self-contained HTML report")
    add_seed(p)
    p.add_argument("--quick", action="store_true",
                   help="fewer samples and angles (every topic kept), and a sweep of each "
                        "parameter's ends only")
    p.add_argument("--no-sweep", action="store_true",
                   help="check the given parameter point alone (by default every parameter "
                        "is swept across its range: its ends, middle and edge values, one at "
                        "a time, plus all at minimum and all at maximum; --set pins one)")
    p.add_argument("--no-known", action="store_true",
                   help="report a Mitsuba built-in's documented findings (docs/conformance.md) "
                        "as fails; by default a Mitsuba built-in named by its type carries them, "
                        "each only inside its own signature, as KNOWN rows")
    p.add_argument("--all-builtins", action="store_true",
                   help="validate every case of the built-in catalogue (phonglab.validate.builtins); "
                        "with --json each finished case is kept in JSON.partial.jsonl at once, "
                        "and a rerun with the same options resumes from it")
    add_arguments(p)         # --workers / --scheduler: where the --all-builtins cases run
    p.set_defaults(func=run)


def _check_inputs(args) -> tuple[dict, tuple[str, ...]]:
    """Every check that needs no Mitsuba, in the order a user would fix them: the --set
    parameters and the topics to run."""
    from .. import outputs   # lazy: outputs loads matplotlib (tonemap), not needed for --help
    every = tuple(dict.fromkeys(TOPICS + EMITTER_TOPICS + INTEGRATOR_TOPICS))
    topics = args.only and check_topics(args.only, every)
    if args.all_builtins:
        if args.bsdf or args.set or args.plugin:
            raise ValidateError("--all-builtins takes no BSDF, --set or --plugin; drop them or "
                                "drop --all-builtins")
    elif not args.bsdf:
        raise ValidateError("name the BSDF to validate (e.g. phonglab validate diffuse) or "
                            "give --all-builtins")
    for path in args.plugin:
        if not Path(path).is_file():
            raise ValidateError(f"plugin file {path!r} does not exist; give the path of a "
                                f"Python file that calls mi.register_bsdf")
    if args.bsdf and args.bsdf.endswith(".xml") and not Path(args.bsdf).is_file():
        raise ValidateError(f"XML file {args.bsdf!r} does not exist")
    if args.report and not args.report.endswith((".html", ".htm")):
        raise ValidateError(f"--report {args.report!r} must end in .html")
    for path, what in ((args.json, "JSON report"), (args.report, "HTML report")):
        if path:
            outputs.check_file(Path(path), what)
            outputs.check_folder(Path(path), what)
    return parse_sets(args.set), topics


def sweep_text(report: Report) -> str:
    """A sweep's table (grouped by point) with the parameters swept and the points refused."""
    from ..verdict import point_label, table_by_point
    sw = report.meta.get("sweep", {})
    if sw.get("points", 1) == 1 and "note" in sw:
        return report.table() + f"\n\n{sw['note']}"
    lines = [f"swept {sw['points']} parameter points of "
             + (", ".join(f"{p['name']} in [{p['lo']:g}, {p['hi']:g}] ({p['source']})"
                          for p in sw["parameters"]) or "no parameter")
             + (f"; pinned: {', '.join(sw['pinned'])}" if sw["pinned"] else ""), "",
             "at the given point:", report.table([r for r in report.rows if not r.point]), "",
             "every point:"]
    lines.append(table_by_point(report.rows))
    probed = [p["name"] for p in sw["parameters"] if p["source"] == "probed"]
    if probed:
        lines += ["", f"the ranges of {', '.join(probed)} were probed (the values the plugin "
                      f"accepts at load time); declare them on the plugin class as "
                      f"PARAMETER_RANGES = {{name: (lo, hi)}} if they are narrower"]
    refused = [r for r in sw["runs"] if r["status"] == "refused"]
    if refused:
        lines += ["", "outside the plugin's range (refused at load time, not run):"]
        lines += [f"  {point_label(r['point'])}: {r['reason']}" for r in refused]
    return "\n".join(lines)


def _all_builtins(args) -> int:
    from ..outputs import write_json   # lazy: numpy, OpenEXR and Pillow, not for --help
    from ..validate import batch

    def progress(d):
        bad = sorted({r["topic"] for r in d["results"] if r["status"] == "fail"})
        known = sorted({r["topic"] for r in d["results"] if r["status"] == "KNOWN"})
        print(f"{d['meta']['case']:<45} {'FAIL ' + ','.join(bad) if bad else 'pass'}"
              + (f"  (KNOWN: {','.join(known)})" if known else "")
              + f"  {d['meta']['wall_seconds']:.1f}s", flush=True)

    # the catalogue's cases are its named points (scripts/conformance.py --sweep sweeps them)
    options = {"seed": args.seed, "quick": args.quick, "topics": args.only}
    log = batch.CaseLog(args.json, options) if args.json else None
    if log is not None and log.done:
        print(f"resuming: {len(log.done)} cases already done ({log.path})", flush=True)
    with runner_from_args(args) as runner:
        result = batch.run_all(options=options, progress=progress, runner=runner, log=log)
    if args.json:
        write_json(args.json, result)
        log.remove()
    print(f"{result['meta']['cases']} cases, {len(result['meta']['failed'])} failing")
    return 1 if result["meta"]["failed"] else 0


def builtin_known(args, params: dict) -> dict | None:
    """The documented causes of a Mitsuba built-in BSDF named by its type (the conformance
    table's findings of that plugin, ``known_for_plugin``), None for anything else (an XML
    file, a ``--plugin`` file, which may register the same name, or ``--no-known``); only the
    findings of cases with the microfacet distribution of ``params``."""
    if args.no_known or args.plugin or args.bsdf.endswith(".xml"):
        return None
    from ..validate.builtins import known_for_plugin   # lazy: the catalogue loads Mitsuba
    return known_for_plugin(args.bsdf, params) or None


def known_of_kind(args, kind: str, shape: dict | None) -> dict | None:
    """As :func:`builtin_known`, for an emitter or integrator built into Mitsuba named by its
    type: the findings of its catalogue's cases (an area emitter's of the same shape only,
    ``phonglab.validate.builtins.kinds.known_for``); phonglab's own plugins (whitted) get none."""
    from ..registration import PLUGINS
    from ..validate.builtins.kinds import known_for

    if (args.no_known or args.plugin or args.bsdf.endswith(".xml")
            or args.bsdf in {name for _, name, _ in PLUGINS}):
        return None
    return known_for(kind, args.bsdf, shape) or None


def known_note(report: Report, label: str, doc: str = "docs/conformance.md") -> str:
    """The line under a table with KNOWN rows from a built-in's documented findings."""
    if not any(r.status == "KNOWN" for r in report.rows):
        return ""
    return (f"\n\nKNOWN rows: documented findings of Mitsuba's {label} ({doc}), "
            f"each matched by its signature (a lane outside it stays a fail); --no-known "
            f"reports them as fails")


def _bsdf(args, params, core, sweep, BSDF):
    """(report, label, text) of a BSDF: its sweep, or the given point with --no-sweep."""
    topics = check_topics(args.only)
    known = builtin_known(args, params)
    if args.no_sweep:
        target = core.prepare(BSDF, args.bsdf, variant=args.variant, params=params,
                              plugins=args.plugin)
        report: Report = core.run(BSDF, target, topics=topics, seed=args.seed, quick=args.quick,
                                  known=known)
        return report, target.label, report.table() + known_note(report, args.bsdf)
    with runner_from_args(args) as runner:
        report = sweep.validate(BSDF, args.bsdf, variant=args.variant, params=params,
                                topics=topics, seed=args.seed, quick=args.quick,
                                plugins=args.plugin, runner=runner, known=known)
    return (report, report.meta["bsdf"],
            sweep_text(report) + known_note(report, args.bsdf))


def _other_kind(args, params, core, not_bsdf: ValidateError):
    """(report, label, text) of an emitter or an integrator, at the given point (the sweep is
    the BSDF kind's): the first kind whose detection function (``is_emitter``,
    ``is_integrator``) accepts ``args.bsdf``; raises the BSDF's error ``not_bsdf`` when it
    names neither."""
    import mitsuba as mi

    from ..registration import register
    from ..validate.emitter import kind as emitter
    from ..validate.integrator import kind as integrator

    if mi.variant() is None:
        register(args.variant)
    shape = params.get("shape")              # before prepare, which takes it out of params
    kinds = ((emitter.is_emitter, emitter.prepare, emitter.EMITTER),
             (integrator.is_integrator, integrator.prepare, integrator.INTEGRATOR))
    target = None
    for detect, prepare, kind in kinds:
        if detect(args.bsdf):
            target = prepare(args.bsdf, variant=args.variant, params=params, plugins=args.plugin)
            break
    else:
        # The BSDF path can stop before the plugin files run (a topic of another kind): each
        # kind's prepare runs them and refuses a file that registers none of its kind.
        for _, prepare, kind in kinds if args.plugin else ():
            try:
                target = prepare(args.bsdf, variant=args.variant, params=params,
                                 plugins=args.plugin)
                break
            except ValidateError:
                continue
        if target is None:
            raise not_bsdf
    report = core.run(kind, target, topics=check_topics(args.only, kind.topics),
                      seed=args.seed, quick=args.quick, known=known_of_kind(args, kind.word, shape))
    note = "" if args.no_sweep else (f"\n\nan {kind.word} is validated at the given parameter "
                                     f"point (the parameter sweep is the BSDF kind's)")
    return report, target.label, report.table() + note + known_note(report, args.bsdf,
                                                        f"docs/conformance-{kind.word}s.md")


def run(args) -> int:
    params, _ = _check_inputs(args)       # topics again per kind, once it is known
    if args.no_sweep and not args.all_builtins and (args.workers != 1 or args.scheduler):
        raise ValidateError("--workers and --scheduler spread the cases of --all-builtins and "
                            "the points of a sweep; drop them or drop --no-sweep")
    if args.all_builtins:
        return _all_builtins(args)
    from ..validate import core, html, sweep   # lazy: Mitsuba and matplotlib load only for a run
    from ..validate.bsdf.kind import BSDF

    try:
        report, label, text = _bsdf(args, params, core, sweep, BSDF)
    except ValidateError as not_bsdf:
        # Not a BSDF: an emitter or an integrator is validated on its own topics.
        report, label, text = _other_kind(args, params, core, not_bsdf)
    print(text)
    if args.json:
        report.write_json(args.json)
    if args.report:
        Path(args.report).parent.mkdir(parents=True, exist_ok=True)
        html.write(report, args.report)
    failing = report.failing
    print(f"\n{label}: {'PASSED' if not failing else f'FAILED ({len(failing)} rows)'} "
          f"in {report.meta['seconds']:.1f} s")
    return 1 if failing else 0
