r"""The ``cost`` topic: time per sample against Mitsuba's ``path`` on the same scene
(:func:`phonglab.validate.integrator.scenes.box`, at the agreement depth, or ``path`` at its
default depth for an integrator of unknown depth).

Informational (the row passes unless the integrator could not be timed): each side renders
once to compile its kernels, then ``cost_repeats`` timed renders of ``cost_spp`` samples per
pixel alternating between the two, and the median of each; the ratio time(integrator) /
time(path) is > 1 when it is slower.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

from ..profile import interleaved_medians
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

    t_i, t_p = interleaved_medians(lambda k: run(integ, 2 + k), lambda k: run(ref, 2 + k),
                                   opts.cost_repeats)
    ratio = t_i / t_p if t_p > 0 else float("nan")
    n = opts.agreement_res ** 2 * opts.cost_spp
    return [Row("cost", "time per sample relative to path", float(ratio), 1.0, None, None,
                "pass" if np.isfinite(ratio) else "fail",
                f"informational: median of {opts.cost_repeats} renders of {n} samples, "
                f"{t_i / n * 1e9:.0f} ns vs path {t_p / n * 1e9:.0f} ns per sample in "
                f"{mi.variant()}" + (f" (max_depth {depth})" if depth else ""),
                {"seconds": t_i, "path_seconds": t_p, "samples": n, "max_depth": depth})]
