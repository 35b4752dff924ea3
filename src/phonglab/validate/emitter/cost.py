r"""The ``cost`` topic: sample_direction throughput relative to the built-in of the same kind.

Informational (the row passes unless the emitter could not be timed): a delta-position light
is timed against ``point``, a directional one against ``directional``, a surface emitter
against ``area`` on a shape of the same type (a mesh loaded from a file: on a cube, also a
mesh), an environment against ``constant``; both over
the same reference points and sample values in the same variant, each once to compile its
kernel, then ``cost_repeats`` timed runs alternating between the two, and the median of each.
The ratio is time(emitter) / time(built-in), so > 1 is slower.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

from ..profile import interleaved_medians
from .config import rng
from .setup import Setup, interaction, point2, view
from .topics import Row

#: Shapes whose class name, lower-cased, is their plugin name and that load without a file.
BUILTIN_SHAPES = ("rectangle", "disk", "sphere", "cube", "cylinder")


def baseline(setup: Setup):
    """(the built-in emitter of the same kind, its name, the object that keeps it alive)."""
    if setup.kind == "position":
        return mi.load_dict({"type": "point", "position": setup.center.tolist()}), "point", None
    if setup.kind == "surface":
        name = setup.shape_name.lower()
        if name not in BUILTIN_SHAPES:          # a mesh from a file (OBJMesh, PLYMesh, ...)
            name = "cube"                       # itself a mesh: the same Mesh sampling code
        shape = mi.load_dict({"type": name, "emitter": {"type": "area"}})
        return shape.emitter(), f"area on a {name}", shape
    name = "directional" if setup.kind == "direction" else "constant"
    scene = mi.load_dict({"type": "scene", "e": {"type": name}, "s": {"type": "sphere"}})
    return scene.emitters()[0], name, scene


def cost(setup: Setup, opts) -> list[Row]:
    n = opts.cost_lanes
    r = rng(opts.seed, "cost")
    p = setup.center + 2.0 * setup.radius * (r.random((n, 3)) - 0.5) + 3.0 * setup.radius
    u = r.random((n, 2))
    base, name, _keep = baseline(setup)
    it, su = interaction(p), point2(u)

    def run(e):
        ds, w = view(e).sample_direction(it, su)
        dr.eval(ds.pdf, w)
        dr.sync_thread()

    t_e, t_b = interleaved_medians(lambda k: run(setup.emitter), lambda k: run(base),
                                   opts.cost_repeats)
    ratio = t_e / t_b if t_b > 0 else float("nan")
    return [Row("cost", f"sample_direction time relative to {name}", float(ratio), 1.0, None,
                None, "pass" if np.isfinite(ratio) else "fail",
                f"informational: median of {opts.cost_repeats} runs over {n} lanes, "
                f"{t_e * 1e3:.2f} ms vs {name} {t_b * 1e3:.2f} ms in {mi.variant()}",
                {"seconds": t_e, "baseline_seconds": t_b, "lanes": n, "baseline": name})]
