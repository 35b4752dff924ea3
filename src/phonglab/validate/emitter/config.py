"""The emitter validator's sizes (quick and default) and its seeded random streams.

Round-off tolerances are the BSDF kind's (:mod:`phonglab.validate.bsdf.config`: ``REL_TOL`` =
2⁻¹⁰ relative, :func:`~phonglab.validate.roundoff.rel_diff` with its floor, and the 8u
perturbation of a direction for a lane's sensitivity): an emitter's identities are float32
chains of the same length (a cone or area pdf, a radiance lookup, a division).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..seeds import Streams

#: The emitter topics' random streams (:mod:`phonglab.validate.seeds`; ``refs``: the reference
#: points every topic shares).
STREAMS = Streams("emitter", {"finite": 31, "weight": 32, "pdf": 33, "chi2": 34, "power": 35,
                              "gradient": 36, "cost": 37, "refs": 38})
#: ``rng(seed, topic)``: the generator of a topic's stream.
rng = STREAMS.rng


@dataclass
class Options:
    """Sizes of one emitter validation run; :func:`options` builds the default or quick ones."""

    quick: bool = False
    seed: int = 0
    n_lanes: int = 4096               #: sample values per reference point (finite/weight/pdf)
    chi2_samples: int = 1_000_000     #: directions per χ² reference point
    chi2_res: int = 40                #: cos θ bins (and 2× as many φ bins)
    chi2_ires: int = 12               #: pdf midpoint nodes per bin and axis (environments)
    chi2_area_nodes: int = 32         #: m: F_m Fibonacci-lattice nodes on the shape (surface)
    power_samples: int = 1_000_000    #: sample_ray calls for the power estimate
    gradient_lanes: int = 4096
    cost_lanes: int = 1 << 18
    cost_repeats: int = 5
    topics: tuple = field(default_factory=tuple)


def options(quick: bool = False, seed: int = 0, topics=()) -> Options:
    """The default sizes (≤ 2 min per emitter on 2 cores) or the quick ones (≤ 15 s)."""
    if not quick:
        return Options(seed=seed, topics=tuple(topics))
    return Options(quick=True, seed=seed, topics=tuple(topics), n_lanes=1024,
                   chi2_samples=200_000, chi2_res=24, chi2_ires=10, chi2_area_nodes=30,
                   power_samples=200_000,
                   gradient_lanes=1024, cost_lanes=1 << 16, cost_repeats=3)
