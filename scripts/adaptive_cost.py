"""Where the time of an adaptive render goes, against ``mi.render`` at the same samples.

Per scene of the bench's oracle rows (:attr:`phonglab.bench.config.Config.adaptive_oracle_scenes`:
each planner-bench scene at its target E, full depth, and the uniform-variance furnace),
adaptive's time over ``mi.render``'s at its mean spp is split into the four factors
wavefront × placement × passes × host whose product it is
(:func:`phonglab.bench.adaptive_sweeps.cost_factors` defines them; a seed is
:func:`~phonglab.bench.adaptive_sweeps.oracle_seed` with ``decompose``), at the bench's
size, without references (~2 min).  ``scripts/adaptive_oracle.py`` times the same seeds at
128², 256² and 512², with the oracles and the errors.

Each configuration is run once first (a warm-up seed, dropped: kernels compiled, memory
touched), then ``--seeds`` seeds, side by side in one process; the factors are of the
medians.  Nothing else should run meanwhile.

    python scripts/adaptive_cost.py [--seeds 3] [--json docs/bench/adaptive_cost.json]
"""

from __future__ import annotations

import argparse

from phonglab.bench.adaptive_sweeps import COST_FACTORS, cost_factors, oracle_seed
from phonglab.bench.config import VARIANT, Config
from phonglab.engine import scenes
from phonglab.engine.outputs import write_json
from phonglab.runtime import quiet_mitsuba, set_variant


def scene_row(name: str, target: float, params: dict, seeds: int) -> dict:
    info = scenes.inspect_scene(name, **params)
    with quiet_mitsuba():
        loaded = scenes.load_scene(info.path, VARIANT, **params)
    integrator = scenes.path_integrator(-1, info)
    oracle_seed(loaded, integrator, target, None, 50, decompose=True)     # warm-up, dropped
    rows = [oracle_seed(loaded, integrator, target, None, s, decompose=True)
            for s in range(seeds)]
    return {"scene": name, "params": params, "target": target, **cost_factors(rows),
            "rows": rows}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--json", metavar="PATH", help="also write the rows as JSON")
    args = ap.parse_args()
    set_variant(VARIANT)
    print("| scene | E | adaptive [s] | mi.render [s] | spp | " + " | ".join(COST_FACTORS)
          + " | total | passes |")
    print("|---|---|---|---|---|" + "---|" * (len(COST_FACTORS) + 2))
    out = []
    for name, (target, params) in Config().adaptive_oracle_scenes.items():
        row = scene_row(name, target, params, args.seeds)
        m = row["medians"]
        print(f"| {name} | {target:g} | {m['seconds']:.3f} | {m['pair_seconds']:.3f} | "
              f"{m['spp']:.0f} | " + " | ".join(f"{row['factors'][k]:.2f}" for k in COST_FACTORS)
              + f" | {row['total']:.2f} | {m['passes']:.0f} |", flush=True)
        out.append(row)
    if args.json:
        write_json(args.json, {"seeds": args.seeds, "rows": out})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
