"""False-failure rate of ``phonglab validate``: correct BSDFs over many seeds.

Runs the validator on the correct plugins ``diffuse``, ``lambert`` and ``phong`` with seeds
0..N-1 (default sizes, or ``--quick``) and prints, per BSDF, the seeds whose run failed and
which topics failed.  Expected: each run fails by chance with probability ≤ ALPHA = 0.01
(Šidák over its statistical tests; the deterministic topics never fail a correct plugin), so
about 3 · N · 0.01 failing runs in all (0.6 for N = 20), and P(≥ 3 failures) ≈ 2 % for N = 20.

    python scripts/false_failures.py [--seeds 20] [--quick] [--bsdf diffuse ...]
"""

from __future__ import annotations

import argparse
import time

from scipy import stats as scipy_stats

from phonglab import stats
from phonglab.validate import validate_bsdf


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--bsdf", action="append", default=None)
    args = ap.parse_args()
    bsdfs = args.bsdf or ["diffuse", "lambert", "phong"]
    failures, runs, t0 = 0, 0, time.perf_counter()
    for name in bsdfs:
        bad = []
        for seed in range(args.seeds):
            report = validate_bsdf(name, seed=seed, quick=args.quick, topics=[
                t for t in ("finite", "eval_pdf", "weight", "pdf", "chi2", "energy",
                            "reciprocity", "component", "gradient")])   # cost is informational
            runs += 1
            if not report.passed:
                bad.append((seed, sorted({r.topic for r in report.failing})))
        failures += len(bad)
        print(f"{name}: {len(bad)} failing runs of {args.seeds}" + (f" {bad}" if bad else ""),
              flush=True)
    expected = runs * stats.ALPHA
    p_tail = float(scipy_stats.binom.sf(failures - 1, runs, stats.ALPHA)) if failures else 1.0
    print(f"total: {failures} failing runs of {runs} ({'quick' if args.quick else 'default'} "
          f"sizes); expected ≤ {expected:.2f} at ALPHA = {stats.ALPHA}; "
          f"P(≥ {failures} | ALPHA) = {p_tail:.3f}; {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
