"""Wall time of ``phonglab validate PLUGIN`` (default and --quick) as a user sees it, and where
it goes.

Each run is a fresh ``phonglab validate`` process timed by :mod:`phonglab.bench.timing`
(start-up, Mitsuba import, kernel compilation -- Dr.Jit's on-disk kernel cache is warm after
a first untimed run of each plugin, and the worker processes' caches after an untimed
``--workers 2`` run -- and every topic of the sweep, its points where the automatic runner
puts them: docs/validate.md); the two modes of one plugin
are timed alternately, ``--repeats`` runs each, the median and the range kept.  Every run writes
its report (``--json``), whose ``meta.profile`` splits the time per topic into kernel
compilation, kernel execution and the rest (:mod:`phonglab.validate.profile`): the table says
which topics hold a plugin above its target.

The plugins: every BSDF type of the BSDF conformance table, validated as a user names it
(``phonglab validate roughplastic``: its defaults swept), a wrapper that needs a nested BSDF
(blendbsdf, twosided, ...) as its table's first case (the dict given to ``validate`` in a fresh
process: its nested plugins pinned, its own parameters swept); and one plugin of each other
kind, a polarized BSDF among them.  Targets on 2 cores, warm cache: a BSDF default
≤ 20 s and --quick ≤ 5 s, an integrator ≤ 45 s and ≤ 10 s (the other kinds: none stated).

    python scripts/validate_timing.py [--repeats 3] [--json docs/bench/validate.json] [NAME ...]

A NAME is a type name, or ``NAME@VARIANT`` for a variant other than llvm_ad_rgb.
``--json`` writes the rows for BENCHMARKS.md (``bench/report.py``'s validate section), each
with when its run started and at which commit (``measured``): a few plugins may be timed again
into the same file.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from phonglab.bench.timing import PHONGLAB, run_child, spread
from phonglab.engine.outputs import write_json

#: One plugin of each kind beyond the BSDF table's (a polarized BSDF in a polarized variant).
OTHERS = ["pplastic@llvm_ad_mono_polarized", "point", "path", "hg", "homogeneous"]
#: (default, --quick) targets in seconds, per kind; None where the issue states none.
TARGETS = {"bsdf": (20.0, 5.0), "integrator": (45.0, 10.0)}
#: Topics listed per row: the most expensive of the default run.
TOP = 3


#: A wrapper validated through the package face in a fresh process (its dict as JSON).
FACE = ("import json, sys; from phonglab.validate import validate; "
        "r = validate(json.loads(sys.argv[1]), variant=sys.argv[2], quick=sys.argv[3] == '1'); "
        "json.dump(r.to_dict(), open(sys.argv[4], 'w'))")


def bsdf_plugins() -> dict[str, object]:
    """Every BSDF type of the BSDF conformance table, in its order: its name, or for a wrapper
    (a case holding a nested plugin) its first case's dict."""
    from phonglab.validate import registry
    out: dict[str, object] = {}
    for case in registry.catalogue("bsdf").cases():
        spec = case.spec if isinstance(case.spec, dict) else {"type": str(case.spec)}
        nested = any(isinstance(v, dict) for v in spec.values())
        out.setdefault(spec["type"], spec if nested else spec["type"])
    return out


def sendable(plugin) -> bool:
    """Whether ``plugin`` can be given to a fresh process (a name, or a dict of plain values)."""
    try:
        json.dumps(plugin)
    except TypeError:
        return False
    return True


def portable(plugin, folder: str):
    """``plugin`` with every loaded ``mi.Bitmap`` (bumpmap's and normalmap's table cases hold
    one) written to an EXR file in ``folder`` and named by its ``filename``, as a user's
    scene names a texture: a dict of plain values a fresh process can be given."""
    if not isinstance(plugin, dict):
        return plugin
    out = {}
    for key, value in plugin.items():
        if isinstance(value, dict):
            value = portable(value, folder)
        elif type(value).__name__ == "Bitmap":
            path = os.path.join(folder, f"texture-{len(os.listdir(folder))}.exr")
            value.write(path)
            key, value = "filename", path
        out[key] = value
    return out


def one_run(plugin, variant: str, quick: bool, folder: str,
            extra: tuple = ()) -> tuple[float, int, dict]:
    """(wall seconds, exit code, the report's meta) of one fresh validate process: the command
    line for a name (``extra`` its further options), the package face for a dict."""
    out = os.path.join(folder, "report.json")
    if isinstance(plugin, dict):
        argv = [sys.executable, "-c", FACE, json.dumps(plugin), variant, "1" if quick else "0",
                out]
    else:
        argv = PHONGLAB + ["validate", plugin, "--variant", variant, "--json", out] \
            + (["--quick"] if quick else []) + list(extra)
    run = run_child(argv, quiet=True, accept=None)
    meta = {}
    if os.path.exists(out):
        with open(out) as f:
            meta = json.load(f).get("meta", {})
        os.remove(out)
    return run.seconds, run.returncode, meta


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("names", nargs="*")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--json", metavar="PATH", help="also write the rows as JSON")
    args = ap.parse_args()
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], text=True,
                            capture_output=True, cwd=Path(__file__).resolve().parents[1]).stdout
    # one run, one label: when it started and at which commit
    measured = datetime.datetime.now(datetime.timezone.utc).strftime(
        "%Y-%m-%d %H:%M UTC at ") + (commit.strip() or "an unknown commit")
    plugins = bsdf_plugins()
    names = args.names or list(plugins) + OTHERS
    rows = []
    print("| plugin | kind | default (s) | --quick (s) | points | top topics (default, s) |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as folder:
        for entry in names:
            name, _, variant = entry.partition("@")
            variant = variant or "llvm_ad_rgb"
            plugin = portable(plugins.get(name, name), folder)
            if not sendable(plugin):
                print(f"| {entry} | not timed: its table case holds a loaded object (a "
                      f"mi.Bitmap), which no fresh process can be given |", flush=True)
                continue
            one_run(plugin, variant, True, folder)         # warm the kernel cache, untimed
            if not isinstance(plugin, dict):
                # and the worker processes' own caches (phonglab.parallel.worker), which a
                # default run's sweep uses when it spreads its points (docs/validate.md)
                one_run(plugin, variant, True, folder, ("--workers", "2"))
            times = {"default": [], "quick": []}
            codes, metas = set(), {}
            for _ in range(args.repeats):
                for mode in ("default", "quick"):
                    seconds, code, meta = one_run(plugin, variant, mode == "quick", folder)
                    times[mode].append(seconds)
                    codes.add(code)
                    metas.setdefault(mode, meta)
            kind = metas["default"].get("kind", "?")
            profile = {t: round(r["seconds"], 2) for t, r in
                       (metas["default"].get("profile") or {}).items() if r.get("seconds")}
            top = sorted(profile.items(), key=lambda kv: -kv[1])[:TOP]
            points = len(metas["default"].get("sweep", {}).get("runs", ())) or 1
            cells = [f"{s['median']:.1f} [{s['spread'][0]:.1f}, {s['spread'][1]:.1f}]"
                     for s in (spread(v, None) for v in times.values())]
            print(f"| {entry} | {kind} | {cells[0]} | {cells[1]} | {points} | "
                  f"{', '.join(f'{t} {s:.1f}' for t, s in top)} |", flush=True)
            rows.append({"plugin": name, "variant": variant, "kind": kind,
                         "where": metas["default"].get("sweep", {}).get("where"),
                         "where_quick": metas["quick"].get("sweep", {}).get("where"),
                         "given": plugin if isinstance(plugin, dict) else None,
                         "repeats": args.repeats, "exit_codes": sorted(codes),
                         "points": points, "profile_default": profile,
                         "profile_quick": {t: round(r["seconds"], 2) for t, r in
                                           (metas["quick"].get("profile") or {}).items()
                                           if r.get("seconds")},
                         "targets": TARGETS.get(kind),
                         "measured": measured,
                         **{f"{m}_seconds": v for m, v in times.items()}})
            if args.json:      # written after every plugin: an interrupted run keeps its rows
                Path(args.json).parent.mkdir(parents=True, exist_ok=True)
                write_json(args.json, rows, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
