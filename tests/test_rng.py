"""Seeds: per-generation generators and spawned run seeds are reproducible and distinct."""

from __future__ import annotations

import numpy as np
import pytest

from emogen.errors import ConfigError
from emogen.rng import check_seed, fresh_seed, generation_rng, spawn_seeds


def test_generation_streams() -> None:
    a = generation_rng(5, 0, 3).random(4)
    np.testing.assert_array_equal(a, generation_rng(5, 0, 3).random(4))
    np.testing.assert_array_equal(
        a,
        np.random.default_rng(np.random.SeedSequence(5, spawn_key=(0, 3))).random(4),
    )
    others = [generation_rng(5, 0, 4), generation_rng(5, 1, 3), generation_rng(6, 0, 3)]
    for rng in others:
        assert not np.array_equal(a, rng.random(4))


def test_spawned_seeds() -> None:
    seeds = spawn_seeds(1, 500)
    assert seeds == spawn_seeds(1, 500)
    assert len(set(seeds)) == 500
    assert all(0 <= s < 2**63 for s in seeds)
    assert spawn_seeds(1, 3) == seeds[:3]
    assert 0 <= fresh_seed() < 2**63


@pytest.mark.parametrize("bad", [-1, 2**63, 1.5, "1", True])
def test_bad_seeds(bad) -> None:
    with pytest.raises(ConfigError, match="seed must be"):
        check_seed(bad)
