r"""The ``cost`` topic: eval and sample throughput relative to the built-in ``diffuse``.

Informational (the row passes unless the BSDF could not be timed): both BSDFs are evaluated
over the same lanes in the same variant, each query once to compile its kernel, then
``cost_repeats`` timed runs alternating between the two, and the median of each.  The ratio is time(BSDF) / time(diffuse), so > 1 is
slower; absolute times depend on the machine and its load.
"""

from __future__ import annotations

import mitsuba as mi
import numpy as np

from ... import probe
from . import lanes
from ..profile import interleaved_medians
from .topics import Row


def cost(bsdf, opts) -> list[Row]:
    r = lanes.rng(opts.seed, "cost")
    n = opts.cost_lanes
    wi = lanes.sphere(r, n)
    wi[:, 2] = np.abs(wi[:, 2])
    wo = lanes.sphere(r, n)
    u1, u2 = r.random(n), r.random((n, 2))
    base = mi.load_dict({"type": "diffuse"})
    rows = []
    for name, fn in (("eval", lambda b: probe.eval(b, wi, wo)),
                     ("sample", lambda b: probe.sample(b, wi, u1, u2))):
        t_bsdf, t_base = interleaved_medians(lambda k: fn(bsdf), lambda k: fn(base),
                                             opts.cost_repeats)
        ratio = t_bsdf / t_base if t_base > 0 else float("nan")
        ok = np.isfinite(ratio)
        rows.append(Row("cost", f"{name} time relative to diffuse", float(ratio), 1.0, None, None,
                        "pass" if ok else "fail",
                        f"informational: median of {opts.cost_repeats} runs over {n} lanes, "
                        f"{t_bsdf * 1e3:.2f} ms vs diffuse {t_base * 1e3:.2f} ms in {mi.variant()}"
                        f" (includes the probe's numpy transfers)",
                        {"seconds": t_bsdf, "diffuse_seconds": t_base, "lanes": n}))
    return rows
