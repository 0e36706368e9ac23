"""Where the GA's random numbers come from: one generator per run and generation, two streams.

Generation g of attempt a of a run with seed ``seed`` draws from its own generator,
:func:`emogen.rng.generation_rng` (seed, a, g) (a ``SeedSequence`` child keyed (a, g)), so any
generation replays from the seed alone. :mod:`emogen.ga.algorithm` asks a :class:`Draws` for
its numbers in a fixed order (slot by slot: slot 3's partner; for each crossover slot the
pair, the crossover mask, the mutation's gene indices and values; then the random faces' gene
indices and values). How a request becomes numbers is the *stream*, recorded with every engine
state and simulation:

* **stream 2** (:class:`BlockDraws`, the default since the GA was written once over runs):
  each run's generator gives one block of doubles, ``rng.random(B)`` (B = N·(3 + K + 2m + 2x),
  more if ever needed: further ``random`` calls continue the same sequence), read front to back.
  A uniform ``u`` is used as is; an integer in [0, k) is ``floor(u·k)``; a pair of distinct
  integers in [0, s) is ``a = floor(u₁·s)``, ``b = floor(u₂·(s − 1))``, ``b += (b ≥ a)``
  (uniform over ordered pairs). Every request takes the same number of doubles whatever the
  value of k, so the arithmetic is vectorised across runs with no per-run Python.
* **stream 1** (:class:`LegacyDraws`): the numbers EmoGen drew before that change — each request
  is the generator's own method (``integers``, ``random``, ``choice(s, 2, replace=False)``)
  called run by run. Kept so that engine states and studies recorded with stream 1
  (``emogen.ga.engine/1``) continue and replay exactly.

Both are public numpy calls only; nothing depends on numpy's internal algorithms beyond what
``Generator.random`` documents.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import numpy as np

from emogen.errors import ConfigError
from emogen.rng import generation_rngs

#: The stream new engines and simulations use.
CURRENT_STREAM = 2
STREAMS = (1, 2)

IntArray = np.ndarray
FloatArray = np.ndarray


class Draws(Protocol):
    """Random numbers for R runs at once; every result has a leading run axis (R, …)."""

    @property
    def runs(self) -> int: ...

    def integers(self, high: int, shape: tuple[int, ...]) -> IntArray:
        """(R, *shape) int64, uniform in [0, high)."""
        ...

    def uniforms(self, shape: tuple[int, ...]) -> FloatArray:
        """(R, *shape) float64, uniform in [0, 1)."""
        ...

    def pairs(self, s: int) -> IntArray:
        """(R, 2) int64: two distinct integers in [0, s), s >= 2, uniform over ordered pairs."""
        ...


def check_stream(stream: object) -> int:
    """A known stream number, or a ConfigError naming the bad value."""
    if (
        isinstance(stream, bool)
        or not isinstance(stream, int | np.integer)
        or stream not in STREAMS
    ):
        raise ConfigError(f"GA stream must be one of {list(STREAMS)}; got {stream!r}")
    return int(stream)


def block_size(n_faces: int, n_genes: int, mutation_genes: int, random_genes: int) -> int:
    """Doubles a generation of stream 2 reads at most (one block per run, no second call)."""
    return n_faces * (3 + n_genes + 2 * mutation_genes + 2 * random_genes)


class BlockDraws:
    """Stream 2: each run's block of ``rng.random`` doubles, read front to back (see module)."""

    def __init__(self, rngs: Sequence[np.random.Generator], size: int) -> None:
        self._rngs = list(rngs)
        self._block = np.empty((len(self._rngs), max(size, 1)))
        for rng, row in zip(self._rngs, self._block, strict=True):
            rng.random(out=row)
        self._at = 0

    @property
    def runs(self) -> int:
        return len(self._rngs)

    def _take(self, n: int) -> FloatArray:
        end = self._at + n
        if end > self._block.shape[1]:  # continue each run's sequence (never needed by the GA)
            more = max(n, self._block.shape[1])
            extra = np.stack([rng.random(more) for rng in self._rngs]).reshape(self.runs, more)
            self._block = np.concatenate([self._block, extra], axis=1)
        out = self._block[:, self._at : end]
        self._at = end
        return out

    def uniforms(self, shape: tuple[int, ...]) -> FloatArray:
        return self._take(int(np.prod(shape, dtype=np.int64))).reshape(self.runs, *shape)

    def integers(self, high: int, shape: tuple[int, ...]) -> IntArray:
        scaled = np.floor(self.uniforms(shape) * high).astype(np.int64)
        out: IntArray = np.minimum(
            scaled, high - 1
        )  # u·high < high in exact arithmetic; guard rounding
        return out

    def pairs(self, s: int) -> IntArray:
        u = self._take(2)
        a = np.minimum(np.floor(u[:, 0] * s).astype(np.int64), s - 1)
        b = np.minimum(np.floor(u[:, 1] * (s - 1)).astype(np.int64), s - 2)
        b = b + (b >= a)
        return np.stack([a, b], axis=1)


class LegacyDraws:
    """Stream 1: the generators' own methods, run by run, as EmoGen drew before stream 2.

    Needed by tests/ga/test_streams.py::test_stream_1_reproduces_offspring_recorded_before_the_redesign
    and tests/study/test_recorded_before.py::test_recorded_study_replays_exactly."""

    def __init__(self, rngs: Sequence[np.random.Generator]) -> None:
        self._rngs = list(rngs)

    @property
    def runs(self) -> int:
        return len(self._rngs)

    def integers(self, high: int, shape: tuple[int, ...]) -> IntArray:
        if shape == ():
            return np.array([rng.integers(high) for rng in self._rngs], dtype=np.int64)
        return np.stack([rng.integers(0, high, size=shape) for rng in self._rngs]).astype(np.int64)

    def uniforms(self, shape: tuple[int, ...]) -> FloatArray:
        return np.stack([rng.random(shape) for rng in self._rngs]).reshape(self.runs, *shape)

    def pairs(self, s: int) -> IntArray:
        return np.stack([rng.choice(s, size=2, replace=False) for rng in self._rngs]).astype(
            np.int64
        )


def generation_draws(
    seeds: Sequence[int] | np.ndarray,
    attempt: int,
    generation: int,
    *,
    stream: int,
    block: int,
) -> Draws:
    """The draws of generation ``generation`` of attempt ``attempt`` for runs with these seeds.

    ``block``: :func:`block_size` of the population (stream 2's block length).
    """
    rngs = generation_rngs(seeds, attempt, generation)
    if check_stream(stream) == 1:
        return LegacyDraws(rngs)
    return BlockDraws(rngs, block)
