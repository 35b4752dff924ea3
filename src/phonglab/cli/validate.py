"""``phonglab validate``: physics conformance of one plugin of any kind of
:data:`phonglab.validate.registry.KINDS` or of every built-in, as a table.

One path for every kind: the variant is set, the ``--plugin`` files run once (a file that
registers a name Mitsuba or phonglab already has is refused), the kind is detected from what
the plugin is (:func:`phonglab.validate.registry.detect`), the plugin is loaded once and
checked across its kind's parameter sweep (:mod:`phonglab.validate.sweep`; ``--no-sweep``: at
the given point).

Exit status: 0 when every row passes (KNOWN rows, with a documented cause, allowed) and every
topic that applies judged something, 1 when a row fails, 2 on bad input (unknown plugin type,
bad --set, missing file, unknown topic): one sentence, checked before any expensive work; 3
when nothing fails but an applicable topic judged nothing (every row of it skipped: "not
covered", :func:`phonglab.validate.core.not_covered`), unless ``--allow-uncovered``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ..parallel import AUTO_MIN_SECONDS, add_arguments, runner_from_args
from ..settings import parse_sets
from ..validate import registry
from ..validate.inputs import ValidateError, check_plugin_file, check_topics
from ..verdict import Report
from .options import add_seed, check_timeout


def _scene_kinds() -> list:
    """The kinds a plugin of a scene file can be picked from by id (``--<tag> ID``)."""
    return [k for k in registry.KINDS if k.scene_noun]


EPILOG = """examples:
  phonglab validate diffuse
  phonglab validate roughconductor          # Mitsuba's documented findings are KNOWN rows
  phonglab validate roughplastic --set alpha=0.25 --set distribution=ggx --quick
  phonglab validate mybsdf --plugin mybsdf.py --report out/mybsdf.html
  phonglab validate material.xml            # a built-in in a file: its findings as by name
""" + "".join(f"  phonglab validate scene.xml --{k.tag} ID     # a scene's {k.scene_noun}, as the "
              f"scene loads it\n" for k in _scene_kinds()) + """\
  phonglab validate twosided --set nested.type=diffuse --set nested.reflectance=0.3,0.4,0.5
  phonglab validate point --quick
  phonglab validate area --set shape.type=sphere --set shape.flip_normals=true
  phonglab validate mylight --plugin mylight.py
  phonglab validate path --quick
  phonglab validate myint --plugin myint.py --json out/myint.json
  phonglab validate --all-builtins --quick --json out/conformance.json
  phonglab validate --all-builtins --scheduler tcp://10.0.0.5:8786 --json out/conformance.json
"""


def _kinds_text() -> str:
    """Each kind and its topics, for the description."""
    return "; ".join(f"{k.article} {k.word} ({k.register}, <{k.tag}>) on {', '.join(k.topics)}"
                     for k in registry.KINDS)


def add_parser(sub) -> None:
    p = sub.add_parser(
        "validate", help=f"check any Mitsuba plugin of these kinds, {registry.accepted()}: "
                         "finiteness, weights, pdf, chi2, energy, reciprocity, gradients, cost",
        description="Validate a Mitsuba 3 plugin (a registered plugin type, a Python plugin "
                    "registered by --plugin, or an XML file holding one) on every topic of "
                    "its kind, detected from the plugin, and print one row per check: "
                    f"{_kinds_text()}. "
                    + "".join(f"--set {o}.type=... gives {k.article} {k.word} its {o}. "
                              for k in registry.KINDS for o in k.load_options)
                    + "Exits 0 when all pass, 1 when a row fails, 2 on bad input, 3 when nothing "
                    "fails but a topic that applies judged nothing (not covered; "
                    "--allow-uncovered accepts it).",
        epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("target", nargs="?", metavar="PLUGIN",
                   help="plugin type name (diffuse, roughplastic, lambert, point, area, path, "
                        "...: of any kind above) or an XML file"
                        + "".join(f"; with --{k.tag} ID, a scene file" for k in _scene_kinds()))
    for k in _scene_kinds():
        p.add_argument(f"--{k.tag}", dest=f"scene_{k.name}", metavar="ID",
                       help=f"validate the {k.word} with this id of the scene file given as "
                            f"PLUGIN, as the scene loads it (its built-in's findings apply as "
                            f"by name; --plugin files run first)")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="a parameter: float, RGB 'r,g,b', string, or nested (nested.type=diffuse)")
    p.add_argument("--plugin", action="append", default=[], metavar="FILE.py",
                   help="a Python file run once after the variant is set; it calls "
                        + ", ".join(k.register for k in registry.KINDS)
                        + " with a name of its own")
    p.add_argument("--variant", help="Mitsuba variant (default llvm_ad_rgb)")
    p.add_argument("--only", action="append", metavar="TOPIC",
                   help="run only this topic (repeatable): "
                        + "; ".join(f"{k.article} {k.word}'s: {', '.join(k.topics)}"
                                    for k in registry.KINDS))
    p.add_argument("--json", metavar="PATH", help="write the report as JSON")
    p.add_argument("--report", metavar="PATH.html", help="write a self-contained HTML report")
    add_seed(p)
    p.add_argument("--quick", action="store_true",
                   help="fewer samples and angles (every topic kept), and a sweep of each "
                        "parameter's ends only")
    p.add_argument("--profile", action="store_true",
                   help="print where the time went: per topic and per sweep point, the wall "
                        "time split into Dr.Jit kernel compilation, kernel execution and the "
                        "rest (the JSON and HTML always carry it as meta.profile)")
    p.add_argument("--no-sweep", action="store_true",
                   help="check the given parameter point alone (by default every parameter "
                        "is swept across its range: its ends, middle and edge values, one at "
                        "a time, plus all at minimum and all at maximum; --set pins one)")
    p.add_argument("--no-known", action="store_true",
                   help="report a Mitsuba built-in's documented findings (docs/conformance*.md) "
                        "as fails; by default a Mitsuba built-in carries them (by its type name, "
                        "as an XML file or a scene's material: identified from what is loaded), "
                        "each only inside its own signature, as KNOWN rows, and a row a "
                        "wrapper inherits from a built-in child's finding reads KNOWN with the "
                        "child named")
    p.add_argument("--allow-uncovered", action="store_true",
                   help="exit 0 even when a topic that applies to the plugin judged nothing "
                        "(every row of it skipped: a topic that could not measure what it "
                        "needs); by default such a run is 'not covered' and exits 3. Topics "
                        "that genuinely do not apply (cost; polarized topics in an RGB "
                        "variant; gradient without AD; the densities of a plugin that has "
                        "none) never count")
    p.add_argument("--all-builtins", action="store_true",
                   help="validate every case of the built-in catalogue (phonglab.validate.registry.catalogue: each kind's table); "
                        "with --json each finished case is kept in JSON.partial.jsonl at once, "
                        "and a rerun with the same options resumes from it")
    p.add_argument("--timeout", type=float, default=None, metavar="SECONDS",
                   help="stop a topic that runs longer than this and report it as one failing "
                        "row ('did not finish within N s'); the other topics still run; a "
                        "--plugin file that takes longer to load is one sentence. Stops "
                        "Python code (a plugin's eval that loops forever), not a compiled "
                        "Dr.Jit kernel; per topic and parameter point, in this process "
                        "(not in --workers processes)")
    # --workers / --scheduler: where a sweep's points and the --all-builtins cases run
    add_arguments(p, auto="a sweep's points after the given one on one process per free "
                          "core (two or more), when the time they spend outside Dr.Jit's "
                          f"kernels is predicted to save {AUTO_MIN_SECONDS:g} s or more, "
                          "else here; "
                          "--all-builtins serially")
    p.set_defaults(func=run)


def _check_inputs(args) -> tuple[dict, tuple[str, ...]]:
    """Every check that needs no Mitsuba, in the order a user would fix them: the --set
    parameters and the topics to run."""
    from ..engine import outputs  # lazy: outputs loads matplotlib (tonemap), not needed for --help
    topics = args.only and check_topics(args.only, registry.every_topic())
    if args.all_builtins:
        if args.target or args.set or args.plugin:
            raise ValidateError("--all-builtins takes no plugin, --set or --plugin; drop them or "
                                "drop --all-builtins")
    elif not args.target:
        raise ValidateError("name the plugin to validate (e.g. phonglab validate diffuse) or "
                            "give --all-builtins")
    for path in args.plugin:
        check_plugin_file(path)
    if args.target and args.target.endswith(".xml") and not Path(args.target).is_file():
        raise ValidateError(f"XML file {args.target!r} "
                            f"{'is a folder' if Path(args.target).is_dir() else 'does not exist'}")
    _check_scene(args)
    check_timeout(args.timeout)
    inputs = [(path, "plugin file (--plugin)") for path in args.plugin]
    if args.target and args.target.endswith(".xml"):
        inputs.append((args.target, "XML file"))
    outputs.check_output_files([(args.json, "JSON report (--json)"),
                                (args.report, "HTML report (--report)")], inputs)
    if args.report is not None and not args.report.endswith((".html", ".htm")):
        raise ValidateError(f"--report {args.report!r} must end in .html")
    if args.all_builtins and args.json is not None:     # the finished cases, kept beside it
        outputs.check_file(Path(args.json + ".partial.jsonl"), "log of finished cases")
    return parse_sets(args.set), topics


def scene_pick(args) -> tuple | None:
    """(kind, id) of the plugin ``--<tag> ID`` picks from the scene file, None without one."""
    picked = [(k, getattr(args, f"scene_{k.name}")) for k in _scene_kinds()
              if getattr(args, f"scene_{k.name}") is not None]
    if len(picked) > 1:
        raise ValidateError(f"{' and '.join(f'--{k.tag} {i}' for k, i in picked)} each name a "
                            f"plugin of the scene; validate one at a time")
    return picked[0] if picked else None


def _check_scene(args) -> None:
    """A scene file goes with --<tag> ID, and --<tag> ID with a scene file (no --set)."""
    from ..validate.inputs import xml_root_tag
    scene = (bool(args.target) and args.target.endswith(".xml")
             and xml_root_tag(args.target) == "scene")
    picked = scene_pick(args)
    if picked is None:
        if scene and _scene_kinds():     # else the kind's detection refuses the <scene>
            raise ValidateError(f"{args.target} is a scene; name the "
                                + " or ".join(f"{k.scene_noun} to validate with --{k.tag} ID "
                                              f"(the id of one of its <{k.tag}> elements)"
                                              for k in _scene_kinds()))
        return
    kind, ident = picked
    if args.all_builtins or not scene:
        raise ValidateError(f"--{kind.tag} {ident} names a {kind.scene_noun} of a scene: give "
                            f"the scene file as PLUGIN (phonglab validate scene.xml --{kind.tag} "
                            f"{ident})")
    if args.set:
        raise ValidateError(f"--set cannot change a scene's {kind.scene_noun}; edit the scene "
                            f"file, or validate the {kind.scene_noun} by its type name with --set")


def sweep_text(report: Report) -> str:
    """A sweep's table (grouped by point) with the parameters swept and the points refused."""
    from ..verdict import point_label, table_by_point
    sw = report.meta.get("sweep", {})
    if sw.get("points", 1) == 1 and "note" in sw:
        return report.table() + f"\n\n{sw['note']}"
    lines = [f"swept {sw['points']} parameter points of "
             + (", ".join(f"{p['name']} in [{p['lo']:g}, {p['hi']:g}] ({p['source']})"
                          for p in sw["parameters"]) or "no parameter")
             + (f"; pinned: {', '.join(sw['pinned'])}" if sw["pinned"] else "")
             + (f"; {_where(sw['where'])}" if sw.get("where") else ""), "",
             "at the given point:", report.table([r for r in report.rows if not r.point]), "",
             "every point:"]
    lines.append(table_by_point(report.rows))
    probed = [p["name"] for p in sw["parameters"] if p["source"] == "probed"]
    if probed:
        lines += ["", f"the ranges of {', '.join(probed)} were probed (the values the plugin "
                      f"accepts at load time); declare them on the plugin class as "
                      f"PARAMETER_RANGES = {{name: (lo, hi)}} if they are narrower"]
    named = [p["name"] for p in sw["parameters"] if p["source"] == "named"]
    if named:
        one = len(named) == 1
        lines += ["", f"the domain{'' if one else 's'} of {', '.join(named)} "
                      f"{'was' if one else 'were'} inferred from {'its name' if one else 'their names'}"
                      f" (the range Mitsuba's plugin reference gives a parameter of that name) "
                      f"and the physical bounds judged there; declare PARAMETER_RANGES = "
                      f"{{name: (lo, hi)}} on the plugin class to give another"]
    if sw.get("advice"):
        lines += ["", "advice (a physical bound exceeded outside the declared or documented "
                      "domain: not a fail):"]
        lines += [f"  {a['topic']}: {a['text']}" for a in sw["advice"]]
    refused = [r for r in sw["runs"] if r["status"] == "refused"]
    if refused:
        lines += ["", "outside the plugin's range (refused at load time, not run):"]
        lines += [f"  {point_label(r['point'])}: {r['reason']}" for r in refused]
    return "\n".join(lines)


def _where(where: dict) -> str:
    """Where a sweep's points ran, in words ("here: 12 jobs predicted to take 9 s ...")."""
    n = where["workers"]
    return (f"on {n} worker processes" if n > 1 else "here") + f" ({where['reason']})"


def _all_builtins(args) -> int:
    from ..engine.outputs import write_json   # lazy: numpy, OpenEXR and Pillow, not for --help
    from ..validate import batch

    def progress(d):
        bad = sorted({r["topic"] for r in d["results"] if r["status"] == "fail"})
        known = sorted({r["topic"] for r in d["results"] if r["status"] == "KNOWN"})
        uncovered = d["meta"].get("not_covered") or []
        print(f"{d['meta']['case']:<45} {'FAIL ' + ','.join(bad) if bad else 'pass'}"
              + (f"  (KNOWN: {','.join(known)})" if known else "")
              + (f"  (not covered: {','.join(uncovered)})" if uncovered else "")
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


def known_note(report: Report, label: str, doc: str = "docs/conformance.md") -> str:
    """The lines under a table with KNOWN rows from a built-in's documented findings: its own,
    and those inherited from built-in children (one line each: row, child, findings)."""
    known = [r for r in report.rows if r.status == "KNOWN"]
    if not known:
        return ""
    label = (report.meta.get("builtin") or {}).get("type", label)
    inherited = [r for r in known if "inherited" in r.details]
    text = ""
    if len(inherited) < len(known):
        text += (f"\n\nKNOWN rows: documented findings of Mitsuba's {label} ({doc}), "
                 f"each matched by its signature (a lane outside it stays a fail); --no-known "
                 f"reports them as fails")
    if inherited:
        text += ("\n\ninherited rows (KNOWN: a documented finding of a Mitsuba built-in "
                 "child, which the child judged alone shows as much: not this plugin's to "
                 "fix; --no-known reports them as fails):")
        seen = set()
        for r in inherited:
            inh = r.details["inherited"]
            line = (f"  {r.topic}: {r.name} <- the child {inh['child']} ({inh['path']}): "
                    f"finding {', '.join(inh['findings'])}")
            if line not in seen:
                seen.add(line)
                text += "\n" + line
    return text


def verdict_counts(report: Report) -> str:
    """The verdict's words for the inherited rows ("2 rows inherited from the child
    roughconductor (nested), KNOWN"), "" for none."""
    inherited = [r.details["inherited"] for r in report.rows
                 if r.status == "KNOWN" and "inherited" in r.details]
    if not inherited:
        return ""
    kids = ", ".join(dict.fromkeys(f"{i['child']} ({i['path']})" for i in inherited))
    return (f"{len(inherited)} row{'s' * (len(inherited) != 1)} inherited from the child "
            f"{kids}, KNOWN")


def which_plugin(name: str, kind, registered) -> str:
    """The line saying which of several plugins a ``--plugin`` run validates ("" for one)."""
    others = [f"the {word} {n!r}" for word, n in registered if n != name]
    if not others:
        return ""
    return (f"\n\nvalidated the {kind.word} {name!r}; the plugin files also registered "
            f"{', '.join(others)} (name one to validate it)")


def validate_one(args, params: dict):
    """(report, label, text) of the plugin ``args.target``: the one pipeline
    (:func:`phonglab.validate.pipeline.validate`), then the text of its report."""
    from ..validate import pipeline   # lazy: Mitsuba loads only for a run
    from ..validate.builtin import BUILTIN

    scene_kind, scene_id = scene_pick(args) or (None, None)
    with runner_from_args(args) as runner:
        report = pipeline.validate(args.target, kind=scene_kind, variant=args.variant,
                                   params=params, plugins=args.plugin, topics=args.only,
                                   seed=args.seed, quick=args.quick,
                                   known=None if args.no_known else BUILTIN,
                                   sweep=not args.no_sweep, runner=runner, scene_id=scene_id)
    kind = registry.by_name(report.meta["kind"])
    text = report.table() if args.no_sweep else sweep_text(report)
    label = report.meta["plugin"]
    if getattr(args, "profile", False):
        from ..validate import profile
        text += "\n\n" + profile.table(report.meta.get("profile", {}),
                                        report.meta.get("sweep", {}).get("runs", ()))
    text += known_note(report, args.target, kind.conformance)
    if scene_id is None:
        text += which_plugin(args.target if isinstance(args.target, str) else label, kind,
                             report.meta.get("registered", ()))
    return report, label, text


def run(args) -> int:
    params, _ = _check_inputs(args)       # topics again per kind, once it is known
    spread = args.workers not in (None, 1) or args.scheduler
    if args.no_sweep and not args.all_builtins and spread:
        raise ValidateError("--workers and --scheduler spread the cases of --all-builtins and "
                            "the points of a sweep; drop them or drop --no-sweep")
    from ..validate.timeout import topic_timeout   # lazy: Mitsuba loads only for a run

    if args.all_builtins:
        with topic_timeout(args.timeout):
            return _all_builtins(args)
    from ..validate import html   # lazy: matplotlib loads only for a run

    with topic_timeout(args.timeout):
        report, label, text = validate_one(args, params)
    print(text)
    if args.json is not None:
        from ..engine.outputs import write_json   # lazy: numpy, OpenEXR and Pillow
        write_json(args.json, report.to_dict())
    if args.report is not None:
        Path(args.report).parent.mkdir(parents=True, exist_ok=True)
        html.write(report, args.report)
    failing, uncovered = report.failing, report.not_covered
    inherited = verdict_counts(report)
    if failing:
        verdict = (f"FAILED ({len(failing)} rows"
                   + (f" to fix in this plugin; {inherited}" if inherited else "") + ")")
    elif uncovered:
        verdict = (f"NOT COVERED: {', '.join(uncovered)} judged nothing (every row skipped; "
                   f"see their reasons)" + ("; accepted by --allow-uncovered"
                                            if args.allow_uncovered else ""))
    else:
        verdict = "PASSED" + (f" ({inherited})" if inherited else "")
    if failing and uncovered:
        verdict += f"; not covered: {', '.join(uncovered)}"
    print(f"\n{label}: {verdict} in {report.meta['seconds']:.1f} s")
    if failing:
        return 1
    return 3 if uncovered and not args.allow_uncovered else 0
