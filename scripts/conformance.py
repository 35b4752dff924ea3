"""Regenerate the conformance tables (``make conformance``): with ``--all-kinds`` every kind's
of phonglab.validate.registry.KINDS, each written to its kind's docs/conformance*.md (the
record's ``conformance``) and the JSON beside it; with ``--kind NAME`` one.

    python scripts/conformance.py --all-kinds [--quick] [--seed S] [--workers N]
    python scripts/conformance.py --kind NAME [--quick] [--seed S] [--only LABEL ...]
        [--sweep | --no-sweep] [--json PATH] [--markdown PATH] [--workers N]
    python scripts/conformance.py --kind NAME --from-json PATH   # markdown only

A kind's cases and findings are its conformance table (phonglab.validate.registry.catalogue(kind),
the records in phonglab.validate.conformance), the renderer is phonglab.validate.markdown; this
driver only runs them and writes the two files.  Each table runs its cases through their
parameter sweep or at their given points as the table says (its ``sweep``; ``--sweep`` and
``--no-sweep`` override it).  Each finished case is kept in ``<json>.partial.jsonl`` at once
(phonglab.validate.batch.CaseLog): an interrupted run loses none, and the same command resumes
from them.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from phonglab.parallel import add_arguments, runner_from_args
from phonglab.validate import batch, registry
from phonglab.validate.markdown import render_markdown, without_plot_data
from phonglab.engine.outputs import write_json


def table(args, name: str, runner) -> None:
    """Validate the cases of the kind ``name``'s table (or read ``--from-json``) and write its
    JSON and markdown."""
    cat = registry.catalogue(name)
    json_path = Path(args.json or cat.json)
    markdown_path = Path(args.markdown or cat.markdown)
    if args.from_json:
        data = json.loads(args.from_json.read_text())
    else:
        def progress(d):
            bad = sorted({f"{r['topic']}:{r['status']}" for r in d["results"]
                          if r["status"] in ("fail", "KNOWN")})
            print(f"{d['meta']['case']:42s} {d['meta']['wall_seconds']:6.1f} s  "
                  f"{', '.join(bad) or 'ok'}", flush=True)
        chosen = [c for c in cat.cases() if not args.only or c.label in args.only]
        sweep = cat.sweep if args.sweep is None else args.sweep
        options = {"kind": name, "seed": args.seed, "quick": args.quick,
                   **({"sweep": True} if sweep else {})}
        log = batch.CaseLog(json_path, options)     # an interrupted run resumes from it
        if log.done:
            print(f"resuming: {len(log.done)} cases already done ({log.path})", flush=True)
        t0 = time.perf_counter()
        data = batch.run_all(chosen, options, progress, runner=runner, log=log)
        data["meta"]["seconds"] = round(time.perf_counter() - t0, 1)
        json_path.parent.mkdir(parents=True, exist_ok=True)
        data = without_plot_data(data)
        write_json(json_path, data, indent=None, separators=(",", ":"), end="\n")
        log.remove()
        print(f"wrote {json_path} ({data['meta']['seconds']} s)")
    markdown_path.parent.mkdir(parents=True, exist_ok=True)
    markdown_path.write_text(render_markdown(data, cat))
    print(f"wrote {markdown_path}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    which = ap.add_mutually_exclusive_group(required=True)
    which.add_argument("--kind", choices=registry.names(), help="one kind's table")
    which.add_argument("--all-kinds", action="store_true",
                       help="every kind's table, each to its own files")
    ap.add_argument("--quick", action="store_true", help="the validator's --quick sizes")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--sweep", action=argparse.BooleanOptionalAction, default=None,
                    help="each case across its parameter sweep, or at its own point only "
                         "(default: as the kind's table says)")
    ap.add_argument("--only", nargs="+", metavar="LABEL", help="validate only these cases")
    ap.add_argument("--json", type=Path, help="default: the kind's docs/conformance*.json")
    ap.add_argument("--markdown", type=Path, help="default: the kind's docs/conformance*.md")
    ap.add_argument("--from-json", type=Path, metavar="JSON",
                    help="render the markdown from this JSON instead of validating")
    add_arguments(ap)       # --workers N / --scheduler ADDRESS: where the cases run (Dask)
    args = ap.parse_args(argv)
    if args.all_kinds:
        given = [flag for flag, value in (("--only", args.only), ("--json", args.json),
                                          ("--markdown", args.markdown),
                                          ("--from-json", args.from_json)) if value]
        if given:
            ap.error(f"{given[0]} names one table's cases or files; give it with --kind NAME, "
                     f"not --all-kinds")
    else:
        cat = registry.catalogue(args.kind)
        unknown = sorted(set(args.only or ()) - {c.label for c in cat.cases()})
        if unknown:
            ap.error(f"unknown case {unknown[0]!r}; the labels are listed by "
                     f"{cat.cases_name}")
    names = registry.names() if args.all_kinds else (args.kind,)
    with runner_from_args(args) as runner:
        for name in names:
            table(args, name, runner)
    return 0


if __name__ == "__main__":
    sys.exit(main())
