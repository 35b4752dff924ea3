"""False failures and false passes of ``phonglab validate`` over many seeds.

False failures: correct BSDFs -- ``diffuse``, ``lambert``, ``phong`` at their defaults, the
narrow lobes that the χ² integration must resolve (GGX ``roughconductor`` α = 0.01 and 0.03 --
Beckmann's pdf is not normalized, a Mitsuba finding -- a
pure Phong lobe at exponents 3000 and 10⁴) and black BSDFs (zero albedo) -- with seeds
0..N−1.  Expected: each run fails by chance with probability ≤ ALPHA = 0.01 (Šidák over its
statistical tests; the deterministic topics never fail a correct plugin), so about
cases · N · 0.01 failing runs in all; the script prints P(≥ that many | ALPHA).  ``diffuse``
and ``lambert`` sample the same cosine density from the same random numbers at one seed, so
their χ² outcomes coincide.

With ``--sweep`` each run is a parameter sweep, over every kind: BSDFs
``diffuse``, ``lambert``, ``phong``, GGX ``roughconductor`` and GGX ``roughplastic`` (the
Beckmann pdfs are a Mitsuba finding) across their parameters, emitters ``point`` and ``area``
across theirs, integrators ``path`` (over ``rr_depth``) and ``direct`` (over its emitter and
BSDF sample counts), the phase function ``hg`` (over g), and two author-written plugins that declare no parameter ranges
(``tests/authors/my_lambert.py``, ``tests/defects_emitter/area_control.py``).  A built-in runs
with every documented cause of its conformance table (the kind's ``known_for``: each explains
only its own signature), as ``phonglab validate`` does; the Šidák family is the points, so
each sweep still fails by chance with probability ≤ ALPHA.  Its planted defects are
``tests/defects/sweep`` (firing only at a parameter edge).

False passes: the planted-defect plugins of ``tests/defects`` (each with one defect a
correct run must catch), the same seeds: a run that passes is a false pass.

The runs are ``phonglab.validate.batch.false_failures`` (``validate_bsdf`` over seeds, every
topic but ``cost``).

    python scripts/false_failures.py [--seeds 20] [--sizes default quick] [--only LABEL ...]
        [--defect-seeds 10] [--sweep] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from scipy import stats as scipy_stats

from phonglab import stats
from phonglab.validate import registry
from phonglab.validate.batch import false_failures

ROOT = Path(__file__).resolve().parent.parent
DEFECTS = ROOT / "tests" / "defects"
AUTHORS = ROOT / "tests" / "authors"
GLOSSY = {"diffuse_reflectance": 0.0, "specular_reflectance": 0.8}

#: label -> (plugin, params): correct BSDFs; every failing run is a false failure.
CORRECT = {
    "diffuse": ("diffuse", {}),
    "lambert": ("lambert", {}),
    "phong": ("phong", {}),
    "roughconductor a=0.01": ("roughconductor", {"alpha": 0.01, "material": "Au",
                                                  "distribution": "ggx"}),
    "roughconductor a=0.03": ("roughconductor", {"alpha": 0.03, "material": "Au",
                                                  "distribution": "ggx"}),
    "phong p=3000": ("phong", {"exponent": 3000.0, **GLOSSY}),
    "phong p=1e4": ("phong", {"exponent": 1e4, **GLOSSY}),
    "diffuse black": ("diffuse", {"reflectance": 0.0}),
    "lambert black": ("lambert", {"reflectance": 0.0}),
    "phong black": ("phong", {"diffuse_reflectance": 0.0, "specular_reflectance": 0.0}),
}


#: label -> (kind, plugin, params, plugin files): correct plugins swept across their
#: parameters (``--sweep``).
SWEPT = {
    "diffuse": ("bsdf", "diffuse", {}, ()),
    "lambert": ("bsdf", "lambert", {}, ()),
    "phong": ("bsdf", "phong", {}, ()),
    "roughconductor ggx": ("bsdf", "roughconductor", {"distribution": "ggx"}, ()),
    "roughplastic ggx": ("bsdf", "roughplastic", {"distribution": "ggx"}, ()),
    "point": ("emitter", "point", {}, ()),
    "area": ("emitter", "area", {}, ()),
    "path": ("integrator", "path", {}, ()),
    "direct": ("integrator", "direct", {}, ()),
    "hg": ("phase", "hg", {}, ()),
    "my_lambert (author)": ("bsdf", "my_lambert", {}, (AUTHORS / "my_lambert.py",)),
    "area_control (author)": ("emitter", "defect_area_control", {},
                              (ROOT / "tests" / "defects_emitter" / "area_control.py",)),
}


#: A planted defect's plugin name where its file registers another than ``defect_<stem>``
#: (plain_lambert.py registers the correct author_lambert beside the defective one).
DEFECT_PLUGINS = {"plain_lambert": "author_lambert_gain"}


def run(spec, params, seeds, quick, plugins=(), sweep=False, kind="bsdf") -> list[dict]:
    """One record per seed: the failing topics."""
    known_for = registry.by_name(kind).part("known_for")
    known = (known_for(spec, params or {}) or None) if sweep and not plugins and known_for else None
    ((_, runs),) = false_failures({"case": (spec, params, known)}, seeds, quick, plugins,
                                  sweep=sweep, kind=kind).items()
    return [{"seed": seed, "failing": failing} for seed, failing in runs]


def tail_p(failures: int, runs: int) -> float:
    """P(≥ failures failing runs of ``runs``) when each fails with probability ALPHA."""
    return float(scipy_stats.binom.sf(failures - 1, runs, stats.ALPHA)) if failures else 1.0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--defect-seeds", type=int, default=10)
    ap.add_argument("--sizes", nargs="+", choices=("default", "quick"),
                    default=["default", "quick"])
    ap.add_argument("--only", nargs="+", metavar="LABEL",
                    help=f"correct cases ({', '.join(CORRECT)}) or defect file stems")
    ap.add_argument("--no-defects", action="store_true")
    ap.add_argument("--defects", type=Path, default=DEFECTS,
                    help="the folder of planted-defect plugins (default tests/defects)")
    ap.add_argument("--sweep", action="store_true",
                    help="each run across the parameter sweep: the SWEPT cases and the "
                         "defects in tests/defects/sweep")
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()
    if args.sweep and args.defects == DEFECTS:
        args.defects = DEFECTS / "sweep"
    chosen = {k: v for k, v in (SWEPT if args.sweep else CORRECT).items()
              if not args.only or k in args.only}
    defects = [] if args.no_defects else sorted(
        p for p in args.defects.glob("*.py") if not args.only or p.stem in args.only)
    result = {"alpha": stats.ALPHA, "sweep": args.sweep, "seeds": args.seeds, "defect_seeds": args.defect_seeds,
              "correct": {}, "defects": {}}
    t_all = time.perf_counter()
    for size in args.sizes:
        quick = size == "quick"
        failures = runs = 0
        for label, case in chosen.items():
            kind, spec, params, files = case if args.sweep else ("bsdf", *case, ())
            t = time.perf_counter()
            recs = run(spec, params, args.seeds, quick, files, sweep=args.sweep, kind=kind)
            per_run = (time.perf_counter() - t) / max(1, len(recs))
            result["correct"].setdefault(label, {})[size] = recs
            result.setdefault("seconds_per_run", {}).setdefault(label, {})[size] = round(per_run, 1)
            bad = [(r["seed"], r["failing"]) for r in recs if r["failing"]]
            failures, runs = failures + len(bad), runs + len(recs)
            print(f"[{size}] {label}: {len(bad)} failing runs of {len(recs)}, {per_run:.1f} s "
                  f"per run" + (f" {bad}" if bad else ""), flush=True)
        if chosen:
            print(f"[{size}] total: {failures} failing runs of {runs}; expected ≤ "
                  f"{runs * stats.ALPHA:.2f} at ALPHA = {stats.ALPHA}; "
                  f"P(≥ {failures} | ALPHA) = {tail_p(failures, runs):.3f}", flush=True)
        for path in defects:
            recs = run(DEFECT_PLUGINS.get(path.stem, f"defect_{path.stem}"), None,
                       args.defect_seeds, quick, [path],
                       sweep=args.sweep)
            result["defects"].setdefault(path.stem, {})[size] = recs
            missed = [r["seed"] for r in recs if not r["failing"]]
            topics = sorted({t for r in recs for t in r["failing"]})
            print(f"[{size}] defect {path.stem}: passed (missed) {len(missed)} of {len(recs)}; "
                  f"failing topics {topics}", flush=True)
    result["seconds"] = round(time.perf_counter() - t_all, 1)
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(result, indent=1) + "\n")
    print(f"{result['seconds']:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
