r"""The ``cost`` topic: time per sample against Mitsuba's ``path`` on the same scene
(:func:`phonglab.validate.integrator.scenes.box`, at the agreement depth, or ``path`` at its
default depth for an integrator of unknown depth).

Informational (the row passes unless the integrator could not be timed): each side renders
once to compile its kernels, then ``cost_repeats`` timed renders of ``cost_spp`` samples per
pixel alternating between the two, and the median of each; the ratio time(integrator) /
time(path) is > 1 when it is slower.
"""

from __future__ import annotations

import statistics
import time

import drjit as dr
import mitsuba as mi
import numpy as np

from . import scenes
from .agreement import depth_of
from .setup import Target
from .topics import Row


def cost(target: Target, opts) -> list[Row]:
    depth, _ = depth_of(target)
    integ = target.make(depth if depth else None)
    ref = mi.load_dict({"type": "path", **({"max_depth": int(depth)} if depth else {})})
    scene = mi.load_dict(scenes.box(opts.agreement_res))

    def run(i, s):
        img = mi.render(scene, spp=opts.cost_spp, seed=s, integrator=i)
        dr.eval(img)
        dr.sync_thread()

    run(integ, 1), run(ref, 1)
    ta, tb = [], []
    for k in range(opts.cost_repeats):
        for i, out in ((integ, ta), (ref, tb)):
            t0 = time.perf_counter()
            run(i, 2 + k)
            out.append(time.perf_counter() - t0)
    t_i, t_p = statistics.median(ta), statistics.median(tb)
    ratio = t_i / t_p if t_p > 0 else float("nan")
    n = opts.agreement_res ** 2 * opts.cost_spp
    return [Row("cost", "time per sample relative to path", float(ratio), 1.0, None, None,
                "pass" if np.isfinite(ratio) else "fail",
                f"informational: median of {opts.cost_repeats} renders of {n} samples, "
                f"{t_i / n * 1e9:.0f} ns vs path {t_p / n * 1e9:.0f} ns per sample in "
                f"{mi.variant()}" + (f" (max_depth {depth})" if depth else ""),
                {"seconds": t_i, "path_seconds": t_p, "samples": n, "max_depth": depth})]
