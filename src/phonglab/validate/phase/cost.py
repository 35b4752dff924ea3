r"""The ``cost`` topic: the time of ``sample`` and of ``eval_pdf`` relative to the built-ins
``isotropic`` and ``hg`` (g = 0.5).

Informational (a row passes unless the phase function could not be timed): each function
over the same (wi, u) lanes in the same variant, once to compile its kernel, then
``cost_repeats`` timed runs alternating between the phase function and the baseline, the
median of each.  The ratio is time(phase function) / time(baseline), so > 1 is slower.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

from ... import probe
from ..profile import interleaved_medians
from . import lanes
from .config import rng
from .topics import Row

BASELINES = (("isotropic", {"type": "isotropic"}), ("hg", {"type": "hg", "g": 0.5}))


def cost(phase, opts) -> list[Row]:
    n = opts.cost_lanes
    r = rng(opts.seed, "cost")
    it = lanes.interaction(lanes.sphere(r, n))
    u1 = mi.Float(r.random(n).astype(np.float32))
    u = r.random((n, 2)).astype(np.float32)
    u2 = mi.Point2f(u[:, 0], u[:, 1])
    wo = probe.to_vectors(lanes.sphere(r, n))
    ctx = lanes.context()

    def run_sample(p):
        out = lanes.view(p).sample(ctx, it, u1, u2)
        dr.eval(out[0], out[2])
        dr.sync_thread()

    def run_eval(p):
        v, q = lanes.view(p).eval_pdf(ctx, it, wo)
        dr.eval(v, q)
        dr.sync_thread()

    def median_times(a, b, fn):
        return interleaved_medians(lambda k: fn(a), lambda k: fn(b), opts.cost_repeats)

    rows = []
    for name, spec in BASELINES:
        base = mi.load_dict(spec)
        ts, bs = median_times(phase, base, run_sample)
        te, be = median_times(phase, base, run_eval)
        ratio = (ts + te) / (bs + be) if bs + be > 0 else float("nan")
        rows.append(Row("cost", f"sample + eval_pdf time relative to {name}", float(ratio), 1.0,
                        None, None, "pass" if np.isfinite(ratio) else "fail",
                        f"informational: median of {opts.cost_repeats} runs over {n} lanes, "
                        f"sample {ts * 1e3:.2f} ms + eval_pdf {te * 1e3:.2f} ms vs {name} "
                        f"{bs * 1e3:.2f} + {be * 1e3:.2f} ms in {mi.variant()}",
                        {"sample_seconds": ts, "eval_seconds": te, "baseline": name,
                         "baseline_sample_seconds": bs, "baseline_eval_seconds": be,
                         "lanes": n}))
    return rows
