"""numpy's ``SeedSequence`` hash for many seeds at once, so per-run generators cost little.

A simulation of R runs needs R generators per generation, each
``default_rng(SeedSequence(seed, spawn_key=key))``. Built one by one, the seed sequence's hash
(pure Python arithmetic in numpy) is most of that cost. :func:`seed_states` computes the same
hash for all seeds together as uint32 array arithmetic, following the algorithm numpy documents
for ``SeedSequence`` (entropy words mixed into a pool of four with a multiply–xorshift hash,
then drawn out with a second hash); :func:`generators` hands each run's state to a PCG64 through
numpy's public ``ISeedSequence`` interface. tests/test_rng.py checks the numbers against
``np.random.SeedSequence`` and ``default_rng`` themselves.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.random.bit_generator import ISeedSequence

from emogen.errors import ConfigError

_POOL = 4
_INIT_A, _MULT_A = 0x43B0D7E5, 0x931E8875
_INIT_B, _MULT_B = 0x8B51F9DD, 0x58F38DED
_MIX_L, _MIX_R = 0xCA01F9DD, 0x4973F715
_SHIFT = 16
_WORD = 0xFFFFFFFF


class _Hasher:
    """The hash constant that advances with every use (the same for every seed)."""

    def __init__(self, start: int, mult: int) -> None:
        self.const, self.mult = start, mult

    def __call__(self, value: np.ndarray) -> np.ndarray:
        value = value ^ np.uint32(self.const)
        self.const = (self.const * self.mult) & _WORD
        value = value * np.uint32(self.const)
        return value ^ (value >> np.uint32(_SHIFT))


def _mix(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    out: np.ndarray = np.uint32(_MIX_L) * x - np.uint32(_MIX_R) * y
    return out ^ (out >> np.uint32(_SHIFT))


def _entropy(seeds: Sequence[int] | np.ndarray, spawn_key: Sequence[int]) -> np.ndarray:
    """(R, 4 + len(key)) uint32: each seed's two words, padded to the pool, then the key."""
    arr = np.asarray(seeds)
    if arr.ndim != 1 or not (arr.size == 0 or np.issubdtype(arr.dtype, np.integer)):
        raise ConfigError(f"seeds must be a 1-d sequence of integers; got {seeds!r}")
    if arr.size and (int(arr.min()) < 0 or int(arr.max()) >= 2**63):
        raise ConfigError(f"seeds must be in [0, 2**63); got {arr.min()}..{arr.max()}")
    for k in spawn_key:
        if not 0 <= int(k) <= _WORD:
            raise ConfigError(f"spawn key words must be in [0, 2**32); got {spawn_key!r}")
    s = arr.astype(np.uint64)
    words = np.zeros((len(s), _POOL + len(spawn_key)), dtype=np.uint32)
    words[:, 0] = (s & np.uint64(_WORD)).astype(np.uint32)
    words[:, 1] = (s >> np.uint64(32)).astype(np.uint32)
    words[:, _POOL:] = np.asarray(spawn_key, dtype=np.uint32)
    return words


def seed_states(seeds: Sequence[int] | np.ndarray, spawn_key: Sequence[int]) -> np.ndarray:
    """(R, 4) uint64: ``SeedSequence(seed, spawn_key=spawn_key).generate_state(4, uint64)``
    for every seed (seeds in [0, 2**63), key words below 2**32)."""
    entropy = _entropy(seeds, spawn_key)
    hash_a = _Hasher(_INIT_A, _MULT_A)
    pool = [hash_a(entropy[:, i]) for i in range(_POOL)]
    for src in range(_POOL):
        for dst in range(_POOL):
            if src != dst:
                pool[dst] = _mix(pool[dst], hash_a(pool[src]))
    for src in range(_POOL, entropy.shape[1]):
        for dst in range(_POOL):
            pool[dst] = _mix(pool[dst], hash_a(entropy[:, src]))
    hash_b = _Hasher(_INIT_B, _MULT_B)
    out = np.stack([hash_b(pool[i % _POOL]) for i in range(2 * _POOL)], axis=1)
    return out[:, 0::2].astype(np.uint64) | (out[:, 1::2].astype(np.uint64) << np.uint64(32))


class _State(ISeedSequence):
    """A seed sequence whose state is already computed (what PCG64 asks of it)."""

    __slots__ = ("_state",)

    def __init__(self, state: np.ndarray) -> None:
        self._state = state

    def generate_state(  # type: ignore[override]  # numpy's stub spells out dtype literals
        self, n_words: int, dtype: type = np.uint32
    ) -> np.ndarray:
        if n_words != _POOL or np.dtype(dtype) != np.uint64:
            raise ConfigError(f"precomputed seed state holds 4 uint64 words; asked {n_words}")
        return self._state


def generators(states: np.ndarray) -> list[np.random.Generator]:
    """One PCG64 generator per row of :func:`seed_states` — those ``default_rng`` would build."""
    # PCG64 accepts any ISeedSequence at run time; its stub names only SeedSequence
    return [
        np.random.Generator(np.random.PCG64(_State(row)))  # type: ignore[arg-type]
        for row in states
    ]
