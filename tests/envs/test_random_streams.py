"""The batched env's compact random streams draw exactly what numpy's Generator draws."""

import numpy as np
import pytest
from gymnasium.utils import seeding

from box_toss_env.envs.random_streams import RandomStreams


@pytest.mark.parametrize("seeds", [[0, 1, 2], [12345, 2**40 + 7, 2**63 - 1, 99]])
def test_streams_match_gymnasium_seeded_generators_bit_for_bit(seeds):
    streams = RandomStreams(len(seeds))
    generators = []
    for i, seed in enumerate(seeds):
        streams.seed(i, seed)
        generators.append(seeding.np_random(seed)[0])
    for width in (11, 1, 5, 11):
        drawn = streams.fill_uniform(np.zeros((len(seeds), width)))
        expected = np.stack([generator.random(width) for generator in generators])
        np.testing.assert_array_equal(drawn, expected)


def test_a_stream_can_be_inspected_as_a_generator_without_advancing_it():
    streams = RandomStreams(2)
    streams.seed(0, 5)
    streams.seed(1, None)
    assert streams.seeded.all()
    copy = streams.generator(0).random(3)
    np.testing.assert_array_equal(streams.fill_uniform(np.zeros((2, 3)))[0], copy)
    np.testing.assert_array_equal(copy, seeding.np_random(5)[0].random(3))
