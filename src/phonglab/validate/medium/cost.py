r"""The ``cost`` topic: the time of one tracking step (``Medium::sample_interaction``: the
medium's ``intersect_aabb``, ``get_majorant`` and ``get_scattering_coefficients``, as every
integrator calls them at each collision) relative to Mitsuba's ``homogeneous`` (σ_t = 1).

Informational (the row passes unless the medium could not be timed): both over the same
rays in the same variant, each once to compile its kernels, then ``cost_repeats`` timed runs
alternating between the medium and the baseline
(:func:`phonglab.validate.profile.interleaved_medians`), the median of each.  The ratio is
time(medium) / time(homogeneous), so > 1 is slower.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

from ..directions import sphere
from ..profile import interleaved_medians
from . import lanes
from .config import rng
from .topics import Row

BASELINE = {"type": "homogeneous", "sigma_t": 1.0}


def cost(medium, opts) -> list[Row]:
    n = opts.cost_lanes
    r = rng(opts.seed, "cost")
    o = (2.0 * r.random((n, 3)) - 1.0) * opts.box
    d = sphere(r, n)
    ray = lanes.ray(o, d, lanes.box_exit(o, d, opts.box))
    u = lanes.floats(r.random(n))
    ch = mi.UInt32(r.integers(0, lanes.channels(), n).astype(np.uint32))
    base = mi.load_dict(BASELINE)

    def step(m):
        mei = lanes.view(m).sample_interaction(ray, u, ch, mi.Bool(True))
        dr.eval(mei.t, mei.sigma_t, mei.sigma_n, mei.sigma_s, mei.combined_extinction)
        dr.sync_thread()

    tm, tb = interleaved_medians(lambda k: step(medium), lambda k: step(base),
                                 opts.cost_repeats)
    ratio = tm / tb if tb > 0 else float("nan")
    return [Row("cost", "sample_interaction time relative to homogeneous", float(ratio), 1.0,
                None, None, "pass" if np.isfinite(ratio) else "fail",
                f"informational: median of {opts.cost_repeats} runs over {n} rays, "
                f"{tm * 1e3:.2f} ms against homogeneous (σ_t = 1) {tb * 1e3:.2f} ms in "
                f"{mi.variant()}", {"seconds": tm, "baseline_seconds": tb, "lanes": n})]
