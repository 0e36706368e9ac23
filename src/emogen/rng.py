"""Seeds and random generators: what is recorded, and how every draw is derived from it.

One integer seed is recorded per GA engine. Generation ``g`` of attempt ``a`` (an attempt is
one run of the GA between restarts, within a trial) draws from its own generator,
``default_rng(SeedSequence(seed, spawn_key=(a, g)))``, so a session replays exactly from its
seed and its recorded selections, whatever was drawn before. Simulations spawn one child
seed per run from the simulation's seed (:func:`spawn_seeds`) and record them.

Every generator is built with numpy's public API, one seed sequence per run and generation
(about 25 µs each); a simulation of R runs and G generations builds R·(G + 1) of them
(benchmarks/bench_simulate.py: part of the 500-run simulation's time in docs/ga.md).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from emogen.errors import ConfigError

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


def generation_rng(seed: int, attempt: int, generation: int) -> np.random.Generator:
    """The generator of generation ``generation`` of attempt ``attempt`` under ``seed``."""
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(attempt, generation)))


def generation_rngs(
    seeds: Sequence[int] | np.ndarray, attempt: int, generation: int
) -> list[np.random.Generator]:
    """:func:`generation_rng` of every seed (one run each), in order."""
    return [generation_rng(int(s), attempt, generation) for s in seeds]


#: Spawn-key words of the observer's choice-noise stream. The GA's generators use two-word
#: keys (attempt, generation); a three-word key can never coincide with one of them.
OBSERVER_KEY = (0x0B5, 0xC401CE)


def observer_rng(seed: int, attempt: int = 0) -> np.random.Generator:
    """The simulated observer's generator for attempt ``attempt`` under ``seed`` (choice noise)."""
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(attempt, *OBSERVER_KEY)))


def observer_rngs(seeds: Sequence[int] | np.ndarray, attempt: int = 0) -> list[np.random.Generator]:
    """:func:`observer_rng` of every seed (one run each), in order."""
    return [observer_rng(int(s), attempt) for s in seeds]
