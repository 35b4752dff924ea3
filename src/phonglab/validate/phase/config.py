"""The phase-function validator's sizes (quick and default) and its seeded random streams.

Round-off tolerances are the BSDF kind's (:mod:`phonglab.validate.roundoff`: ``REL_TOL`` =
2⁻¹⁰ relative, ``rel_diff`` with its floor, the 8u perturbation of a direction for a lane's
sensitivity): a phase function's identities are float32 chains of the same length.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..seeds import Streams

#: The phase-function topics' random streams (:mod:`phonglab.validate.seeds`).
STREAMS = Streams("phase", {"finite": 41, "weight": 42, "pdf": 43, "chi2": 44,
                            "normalization": 45, "reciprocity": 46, "gradient": 47, "cost": 48})
#: ``rng(seed, topic)``: the generator of a topic's stream.
rng = STREAMS.rng


@dataclass
class Options:
    """Sizes of one phase-function validation run; :func:`options` builds them."""

    quick: bool = False
    seed: int = 0
    n_lanes: int = 1 << 16            #: (wi, u) or (wi, wo) lanes of the identity topics
    chi2_samples: int = 1_000_000     #: directions per χ² incidence
    chi2_res: int = 41                #: cos θ rows of the χ² grid (⌊res/2⌋ φ columns)
    chi2_ires: int = 4                #: Gauss-Legendre nodes per panel and axis, first level
    chi2_ires_max: int = 64           #: ... and the finest level
    norm_nodes: int = 16              #: Gauss-Legendre nodes per panel (normalization)
    gradient_lanes: int = 4096
    cost_lanes: int = 1 << 18
    cost_repeats: int = 5
    topics: tuple = field(default_factory=tuple)


def options(quick: bool = False, seed: int = 0, topics=()) -> Options:
    """The default sizes or the quick ones (a few seconds per phase function)."""
    if not quick:
        return Options(seed=seed, topics=tuple(topics))
    return Options(quick=True, seed=seed, topics=tuple(topics), n_lanes=1 << 13,
                   chi2_samples=200_000, chi2_res=25, chi2_ires_max=32, norm_nodes=8,
                   gradient_lanes=1024, cost_lanes=1 << 16, cost_repeats=3)
