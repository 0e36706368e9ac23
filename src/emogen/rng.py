"""Seeds and random generators: what is recorded, and how every draw is derived from it.

One integer seed is recorded per GA engine. Generation ``g`` of trial ``t`` (a trial is one
run of the GA between resets) draws from its own generator,
``default_rng(SeedSequence(seed, spawn_key=(t, g)))``, so a session replays exactly from its
seed and its recorded selections, whatever was drawn before. Simulations spawn one child
seed per run from the simulation's seed (:func:`spawn_seeds`) and record them.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from emogen.errors import ConfigError
from emogen.seeding import generators, seed_states

# Seeds are kept below 2**63 so that they fit signed 64-bit columns (Parquet, SQL, pandas).
SEED_BITS = 63


def check_seed(seed: object, name: str = "seed") -> int:
    """An integer seed in [0, 2**63), or a ConfigError naming the bad value."""
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer):
        raise ConfigError(f"{name} must be a non-negative integer; got {seed!r}")
    value = int(seed)
    if not 0 <= value < 2**SEED_BITS:
        raise ConfigError(f"{name} must be in [0, 2**{SEED_BITS}); got {value}")
    return value


def _to_seed(ss: np.random.SeedSequence) -> int:
    return int(ss.generate_state(1, np.uint64)[0] >> np.uint64(64 - SEED_BITS))


def fresh_seed() -> int:
    """A new seed from the operating system's entropy (record it: it is not reproducible)."""
    return _to_seed(np.random.SeedSequence())


def spawn_seeds(seed: int, n: int) -> list[int]:
    """``n`` independent child seeds of ``seed`` (``SeedSequence.spawn``), as recordable ints."""
    return [_to_seed(child) for child in np.random.SeedSequence(check_seed(seed)).spawn(n)]


def generation_rng(seed: int, trial: int, generation: int) -> np.random.Generator:
    """The generator of generation ``generation`` of trial ``trial`` under ``seed``."""
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(trial, generation)))


def generation_rngs(
    seeds: Sequence[int] | np.ndarray, trial: int, generation: int
) -> list[np.random.Generator]:
    """:func:`generation_rng` for many seeds at once: the same generators (same numbers), their
    seed sequences hashed together (:func:`emogen.seeding.seed_states`) instead of one by one."""
    return generators(seed_states(seeds, (trial, generation)))


#: Spawn-key words of the observer's choice-noise stream. The GA's generators use two-word
#: keys (trial, generation); a three-word key can never coincide with one of them.
OBSERVER_KEY = (0x0B5, 0xC401CE)


def observer_rng(seed: int, trial: int = 0) -> np.random.Generator:
    """The simulated observer's generator for trial ``trial`` under ``seed`` (choice noise)."""
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(trial, *OBSERVER_KEY)))


def observer_rngs(seeds: Sequence[int] | np.ndarray, trial: int = 0) -> list[np.random.Generator]:
    """:func:`observer_rng` for many seeds at once (same generators, hashed together)."""
    return generators(seed_states(seeds, (trial, *OBSERVER_KEY)))
