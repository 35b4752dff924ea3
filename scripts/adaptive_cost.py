"""Where the time of an adaptive render goes, against ``mi.render`` at the same samples.

Per scene of the bench's oracle rows (:attr:`phonglab.bench.config.Config.adaptive_oracle_scenes`:
each planner-bench scene at its target E, full depth, and the uniform-variance furnace),
adaptive's time over ``mi.render``'s at its mean spp is split into four factors whose product
it is:

* **wavefront**: :class:`phonglab.engine.wavefront.Wavefront` tracing uniform counts in one pass
  (the same total) over ``mi.render`` (its filter splats and moments against the film's);
* **placement**: the wavefront tracing adaptive's final counts in one pass, without the exact
  squared-weight sums Q, over the uniform counts: what the pixels that get the samples cost;
* **passes**: the render's own tracing (:attr:`AdaptiveResult.passes`, ``trace_seconds``)
  over that one pass: several launches, and Q over the pilot and its edge pixels later;
* **host**: the whole render over its tracing: developing the image, the estimates, the
  allocation.

Each configuration is run once first (a warm-up seed, dropped: kernels compiled, memory
touched), then ``--seeds`` seeds, side by side in one process; the factors are of the
medians.  Nothing else should run meanwhile.

    python scripts/adaptive_cost.py [--seeds 3] [--json docs/bench/adaptive_cost.json]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from phonglab.bench.config import VARIANT, Config
from phonglab.engine import adaptive, render, scenes
from phonglab.engine.outputs import write_json
from phonglab.engine.wavefront import Wavefront
from phonglab.runtime import quiet_mitsuba, set_variant

FACTORS = ("wavefront", "placement", "passes", "host")


def _timed(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def one_seed(loaded, integrator, target: float, seed: int) -> dict:
    """One adaptive render and the three references its factors need."""
    t0 = time.perf_counter()
    result = adaptive.render_adaptive(loaded, target, seed=seed, integrator=integrator)
    total = time.perf_counter() - t0
    spp = max(1, round(result.total_spp))
    uniform = _timed(lambda: render.render_scene(loaded, spp, seed=seed + 1000,
                                                 integrator=integrator))
    counts = result.spp.ravel().astype(np.int64)
    flat = np.full(counts.size, counts.sum() // counts.size, dtype=np.int64)
    flat[:counts.sum() - flat.sum()] += 1                    # the same total, spread evenly
    one_pass = _timed(lambda: Wavefront(loaded, integrator).trace(counts, seed + 2000))
    one_flat = _timed(lambda: Wavefront(loaded, integrator).trace(flat, seed + 3000))
    return {"seconds": total, "trace_seconds": sum(p["trace_seconds"] for p in result.passes),
            "mi_render_seconds": uniform, "one_pass_seconds": one_pass,
            "one_pass_uniform_seconds": one_flat, "spp": result.total_spp,
            "passes": len(result.passes)}


def scene_row(name: str, target: float, params: dict, seeds: int) -> dict:
    info = scenes.inspect_scene(name, **params)
    with quiet_mitsuba():
        loaded = scenes.load_scene(info.path, VARIANT, **params)
    integrator = scenes.path_integrator(-1, info)
    one_seed(loaded, integrator, target, seed=70)               # warm-up, dropped
    rows = [one_seed(loaded, integrator, target, seed=80 + s) for s in range(seeds)]
    m = {k: statistics.median(r[k] for r in rows) for k in rows[0]}
    factors = {"wavefront": m["one_pass_uniform_seconds"] / m["mi_render_seconds"],
               "placement": m["one_pass_seconds"] / m["one_pass_uniform_seconds"],
               "passes": m["trace_seconds"] / m["one_pass_seconds"],
               "host": m["seconds"] / m["trace_seconds"]}
    return {"scene": name, "params": params, "target": target, "medians": m,
            "factors": factors, "total": m["seconds"] / m["mi_render_seconds"], "rows": rows}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--json", metavar="PATH", help="also write the rows as JSON")
    args = ap.parse_args()
    set_variant(VARIANT)
    print("| scene | E | adaptive [s] | mi.render [s] | spp | " + " | ".join(FACTORS)
          + " | total | passes |")
    print("|---|---|---|---|---|" + "---|" * (len(FACTORS) + 2))
    out = []
    for name, (target, params) in Config().adaptive_oracle_scenes.items():
        row = scene_row(name, target, params, args.seeds)
        m = row["medians"]
        print(f"| {name} | {target:g} | {m['seconds']:.3f} | {m['mi_render_seconds']:.3f} | "
              f"{m['spp']:.0f} | " + " | ".join(f"{row['factors'][k]:.2f}" for k in FACTORS)
              + f" | {row['total']:.2f} | {m['passes']:.0f} |", flush=True)
        out.append(row)
    if args.json:
        write_json(args.json, {"seeds": args.seeds, "rows": out})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
