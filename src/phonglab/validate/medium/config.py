"""The medium validator's sizes (quick and default) and its seeded random streams.

Round-off tolerances are the other kinds' (:mod:`phonglab.validate.roundoff`: ``REL_TOL`` =
2⁻¹⁰ relative): a medium's coefficients are short float32 chains (a volume lookup, a scale,
a difference against the majorant).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..seeds import Streams

#: The medium topics' random streams (:mod:`phonglab.validate.seeds`; ``probe``: the rays every
#: topic shares).
STREAMS = Streams("medium", {"probe": 51, "finite": 52, "majorant": 53, "albedo": 54,
                             "transmittance": 55, "bounds": 56, "flags": 57, "overrides": 58,
                             "phase": 59, "cost": 60,
                             "gradient": 61})
#: ``rng(seed, topic)``: the generator of a topic's stream.
rng = STREAMS.rng


@dataclass
class Options:
    """Sizes of one medium validation run; :func:`options` builds them."""

    quick: bool = False
    seed: int = 0
    #: half-width of the probe box [−box, box]³ the rays start in and are clipped to: every
    #: point the topics look at lies in it (a Mitsuba gridvolume fills [0, 1]³ by default)
    box: float = 2.0
    n_rays: int = 1 << 15             #: probe rays (one in-bounds point and one outside each)
    tracking_rays: int = 24           #: rays of the transmittance topic
    tracking_lanes: int = 8192        #: tracking walks per ray and estimator
    tracking_steps: int = 20000       #: a walk still going after this many collisions fails
    quad_panels: int = 64             #: Gauss-Legendre panels along a ray (optical depth)
    quad_nodes: int = 4               #: nodes per panel (and twice as many for the error)
    override_lanes: int = 4096        #: lanes an override is compared with the base class on
    gradient_lanes: int = 4096        #: in-bounds interactions the gradient topic sums over
    cost_lanes: int = 1 << 16
    cost_repeats: int = 5
    topics: tuple = field(default_factory=tuple)


def options(quick: bool = False, seed: int = 0, topics=()) -> Options:
    """The default sizes or the quick ones (a few seconds per medium)."""
    if not quick:
        return Options(seed=seed, topics=tuple(topics))
    return Options(quick=True, seed=seed, topics=tuple(topics), n_rays=1 << 13,
                   tracking_rays=12, tracking_lanes=4096, quad_panels=48,
                   override_lanes=1024, gradient_lanes=1024, cost_lanes=1 << 14, cost_repeats=3)
