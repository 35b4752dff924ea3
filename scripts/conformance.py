"""Regenerate docs/conformance.json and docs/conformance.md (``make conformance``), and with
``--kind emitter|integrator`` docs/conformance-emitters.* and docs/conformance-integrators.*.

    python scripts/conformance.py [--kind bsdf] [--quick] [--seed S] [--only LABEL ...]
        [--json docs/conformance.json] [--markdown docs/conformance.md] [--workers N]
    python scripts/conformance.py --from-json docs/conformance.json   # markdown only

A kind's cases and findings are its conformance table (phonglab.validate.registry.catalogue(kind),
the records in phonglab.validate.conformance), the renderer is phonglab.validate.markdown; this
driver only runs them and writes the two files.  Each finished case is kept in
``<json>.partial.jsonl`` at once (phonglab.validate.batch.CaseLog): an interrupted run loses
none, and the same command resumes from them.
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


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--kind", choices=registry.names(), default="bsdf",
                    help="which kind's table: built-in BSDFs (default), emitters, integrators, ...")
    ap.add_argument("--quick", action="store_true", help="the validator's --quick sizes")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--sweep", action="store_true",
                    help="each case across its parameter sweep (default: its own point only)")
    ap.add_argument("--only", nargs="+", metavar="LABEL", help="validate only these cases")
    ap.add_argument("--json", type=Path, help="default: the kind's docs/conformance*.json")
    ap.add_argument("--markdown", type=Path, help="default: the kind's docs/conformance*.md")
    ap.add_argument("--from-json", type=Path, metavar="JSON",
                    help="render the markdown from this JSON instead of validating")
    add_arguments(ap)       # --workers N / --scheduler ADDRESS: where the cases run (Dask)
    args = ap.parse_args(argv)
    cat = registry.catalogue(args.kind)
    args.json = args.json or Path(cat.json)
    args.markdown = args.markdown or Path(cat.markdown)
    labels = {c.label for c in cat.cases()}
    unknown = sorted(set(args.only or ()) - labels)
    if unknown:
        ap.error(f"unknown case {unknown[0]!r}; the labels are listed by "
                 f"{cat.cases_name}")
    if args.from_json:
        data = json.loads(args.from_json.read_text())
    else:
        def progress(d):
            bad = sorted({f"{r['topic']}:{r['status']}" for r in d["results"]
                          if r["status"] in ("fail", "KNOWN")})
            print(f"{d['meta']['case']:42s} {d['meta']['wall_seconds']:6.1f} s  "
                  f"{', '.join(bad) or 'ok'}", flush=True)
        chosen = [c for c in cat.cases() if not args.only or c.label in args.only]
        options = {"seed": args.seed, "quick": args.quick, "sweep": args.sweep}
        if args.kind != "bsdf":                  # the BSDF JSON keeps its options as they were
            options = {"kind": args.kind, "seed": args.seed, "quick": args.quick,
                       **({"sweep": True} if args.sweep else {})}
        log = batch.CaseLog(args.json, options)     # an interrupted run resumes from it
        if log.done:
            print(f"resuming: {len(log.done)} cases already done ({log.path})", flush=True)
        t0 = time.perf_counter()
        with runner_from_args(args) as runner:
            data = batch.run_all(chosen, options, progress, runner=runner, log=log)
        data["meta"]["seconds"] = round(time.perf_counter() - t0, 1)
        args.json.parent.mkdir(parents=True, exist_ok=True)
        data = without_plot_data(data)
        write_json(args.json, data, indent=None, separators=(",", ":"), end="\n")
        log.remove()
        print(f"wrote {args.json} ({data['meta']['seconds']} s)")
    args.markdown.parent.mkdir(parents=True, exist_ok=True)
    args.markdown.write_text(render_markdown(data, cat))
    print(f"wrote {args.markdown}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
