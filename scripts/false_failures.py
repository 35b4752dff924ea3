"""False-failure rate of ``phonglab validate``: correct BSDFs over many seeds.

Runs the validator on the correct plugins ``diffuse``, ``lambert`` and ``phong`` with seeds
0..N-1 (default sizes, or ``--quick``) and prints, per BSDF, the seeds whose run failed and
which topics failed.  Expected: each run fails by chance with probability ≤ ALPHA = 0.01
(Šidák over its statistical tests; the deterministic topics never fail a correct plugin), so
about 3 · N · 0.01 failing runs in all (0.6 for N = 20), and P(≥ 3 failures) ≈ 2 % for N = 20.
``diffuse`` and ``lambert`` sample the same cosine density from the same random numbers at
one seed, so their χ² outcomes coincide: a chance failure of one is usually one of both.

    python scripts/false_failures.py [--seeds 20] [--quick] [--bsdf diffuse ...]
"""

from __future__ import annotations

import argparse
import time

from scipy import stats as scipy_stats

from phonglab import stats
from phonglab.validate.batch import false_failures


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--bsdf", action="append", default=None)
    args = ap.parse_args()
    bsdfs = args.bsdf or ["diffuse", "lambert", "phong"]
    t0 = time.perf_counter()
    result = false_failures(bsdfs, args.seeds, args.quick)
    for name, bad in result.items():
        print(f"{name}: {len(bad)} failing runs of {args.seeds}" + (f" {bad}" if bad else ""))
    failures = sum(len(b) for b in result.values())
    runs = len(bsdfs) * args.seeds
    expected = runs * stats.ALPHA
    p_tail = float(scipy_stats.binom.sf(failures - 1, runs, stats.ALPHA)) if failures else 1.0
    print(f"total: {failures} failing runs of {runs} ({'quick' if args.quick else 'default'} "
          f"sizes); expected ≤ {expected:.2f} at ALPHA = {stats.ALPHA}; "
          f"P(≥ {failures} | ALPHA) = {p_tail:.3f}; {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
