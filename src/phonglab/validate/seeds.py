r"""The random streams of a validation run: one per (kind, topic), from the run's seed.

Every random number a topic draws on the host comes from ``np.random.default_rng([seed, n])``
(:meth:`Streams.rng`), where ``seed`` is the run's ``--seed`` and n the topic's stream number,
declared by its kind (:class:`Streams`); a topic that needs further streams of its own draws
``[seed, n, k]`` (k = 1, 2, ...).  numpy's ``SeedSequence`` hashes the entropy list into the
generator's state, so different lists give independent streams: a topic's numbers depend on
the seed and its own n alone, never on which other topics run or in which order, and a fixed
seed gives every topic the same lanes on every run.  A sampler that takes one integer seed
(:func:`phonglab.probe.sample_random`) gets seed + 1000·n + k (:meth:`Streams.int_seed`,
k < 1000), distinct per topic within a run.

A number belongs to one (kind, topic): :class:`Streams` refuses one that another kind's topic
already holds, so no two topics of any kinds share a stream.  Topics that must see the same
lanes share them by drawing from one topic's stream (the BSDF ``weight`` and ``pdf`` rows
check the same samples, drawn from ``weight``'s).  A stream number, once given, is kept: a new
number would change every fixed-seed outcome of its topic.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

import numpy as np

#: Every stream number declared so far -> its (kind, topic).
_TAKEN: dict[int, tuple[str, str]] = {}


@dataclass(frozen=True)
class Streams:
    """One kind's topics -> their stream numbers (unique across every kind's)."""

    kind: str
    numbers: Mapping[str, int]

    def __post_init__(self):
        mine: dict[int, tuple[str, str]] = {}
        for topic, n in self.numbers.items():
            owner = mine.setdefault(int(n), _TAKEN.get(int(n), (self.kind, topic)))
            if owner != (self.kind, topic):
                raise ValueError(f"stream {n} of the {self.kind} topic {topic!r} is taken by the "
                                 f"{owner[0]} topic {owner[1]!r}; give it an unused number")
        _TAKEN.update(mine)

    def key(self, seed: int, topic: str, *part: int) -> list[int]:
        """The entropy of ``topic``'s stream at the run's ``seed`` (``part``: a further stream
        of the topic's own)."""
        return [int(seed), self.numbers[topic], *part]

    def rng(self, seed: int, topic: str, *part: int) -> np.random.Generator:
        """The generator of ``topic``'s stream at the run's ``seed``."""
        return np.random.default_rng(self.key(seed, topic, *part))

    def int_seed(self, seed: int, topic: str, part: int = 0) -> int:
        """One integer seed of ``topic`` at the run's ``seed``, for a sampler that takes one."""
        return int(seed) + 1000 * self.numbers[topic] + part


def taken() -> dict[int, tuple[str, str]]:
    """Every stream number declared so far -> its (kind, topic)."""
    return dict(_TAKEN)
