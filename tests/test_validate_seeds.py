"""The validator's random streams (phonglab.validate.seeds): one per (kind, topic), none
shared between kinds, each a function of the run's seed and its own number alone."""

from __future__ import annotations

import numpy as np
import pytest

from phonglab.validate import registry, seeds
from phonglab.validate.bsdf import lanes
from phonglab.validate.emitter import config as emitter_config
from phonglab.validate.medium import config as medium_config
from phonglab.validate.phase import config as phase_config

STREAMS = {"bsdf": lanes.STREAMS, "emitter": emitter_config.STREAMS,
           "phase": phase_config.STREAMS, "medium": medium_config.STREAMS}
#: Streams a kind's topics share that are no topic themselves.
SHARED = {("emitter", "refs"), ("medium", "probe")}


def test_every_kinds_streams_are_its_topics_and_no_number_is_shared():
    taken = seeds.taken()
    declared = [(s.kind, t) for s in STREAMS.values() for t in s.numbers]
    assert sorted(set(taken.values())) == sorted(declared)       # each (kind, topic) once
    assert len(taken) == len(declared)                            # ... with its own number
    for kind, streams in STREAMS.items():
        topics = set(registry.by_name(kind).topics)
        assert set(streams.numbers) - topics == {t for k, t in SHARED if k == kind}, kind


def test_a_number_another_kinds_topic_holds_is_refused():
    with pytest.raises(ValueError, match="stream 14 of the planted topic 'x' is taken by the "
                                         "bsdf topic 'chi2'; give it an unused number"):
        seeds.Streams("planted", {"x": 14})
    seeds.Streams("bsdf", {"chi2": 14})                # the same declaration again holds
    assert seeds.taken()[14] == ("bsdf", "chi2")


def test_a_topics_stream_depends_on_the_seed_and_its_own_number_alone():
    first = emitter_config.rng(3, "chi2").random(4)
    np.testing.assert_array_equal(first, emitter_config.rng(3, "chi2").random(4))
    np.testing.assert_array_equal(first, np.random.default_rng([3, 34]).random(4))
    assert not np.array_equal(first, emitter_config.rng(4, "chi2").random(4))
    assert not np.array_equal(first, emitter_config.rng(3, "pdf").random(4))
    assert not np.array_equal(first, emitter_config.rng(3, "chi2", 1).random(4))
    # the same topic name of two kinds: two streams
    assert not np.array_equal(lanes.rng(3, "chi2").random(4), first)
    assert lanes.STREAMS.int_seed(3, "chi2", 2) == 3 + 1000 * 14 + 2


def test_a_refused_declaration_takes_no_number():
    with pytest.raises(ValueError, match="stream 901 of the planted topic 'b' is taken by the "
                                         "planted topic 'a'"):
        seeds.Streams("planted", {"a": 901, "b": 901})
    assert 901 not in seeds.taken()
