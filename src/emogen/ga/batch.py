"""Algorithm 1 (and the classical variant) for many runs at once, exactly as run by run.

:func:`next_generation_batch` advances R independent runs — genes ``(R, N, K)`` — in one call;
run r draws from its own generator ``rngs[r]``. The result is *identical*, bit for bit, to
``next_generation(genes[r], elite[r], others[r], g, rng=rngs[r])`` for every r (likewise
:func:`classical_next_generation_batch` and :func:`~emogen.ga.classical.classical_next_generation`),
so a vectorised simulation reproduces the engine's runs from the same seeds. Every run of a
batch must have the same number of selections (the simulated observers' schedules depend on the
generation only).

How. The operators' arithmetic is vectorised across runs. The draws are not shared: each run's
draws come from its own generator, in the order :func:`~emogen.ga.step.next_generation` makes
them. Two ways to get them, giving the same numbers:

* **public** — call the generator's methods (``choice``, ``random``, ``integers``) run by run,
  exactly as the one-run functions do;
* **emulated** (fast path) — a generation's sequence of draws is fixed by (g, |selection|,
  N, K, m, x), so each draw's place in a fresh PCG64's raw 64-bit stream is known in advance
  (the "tape"). We take each run's whole raw stream with one ``random_raw`` call and turn it
  into values with numpy's own formulas, vectorised over runs: doubles are
  ``(raw >> 11) · 2⁻⁵³``; bounded integers are Lemire's multiply-shift on 32-bit halves (low
  half first, the high half buffered for the next 32-bit draw); ``choice(s, 2,
  replace=False)`` is Floyd's algorithm followed by a shuffle. A Lemire draw that could need
  rejection (probability < k / 2³², about 10⁻⁸) marks its run, which is then redone through
  the public path. The emulation is checked against the public path the first time it is used
  in a process (:func:`emulation_available`); if numpy ever draws differently, every run takes
  the public path — slower, never different.

Generators must be fresh PCG64 generators (as :func:`emogen.rng.generation_rng` makes) for the
fast path; any other generator simply takes the public path. Either way the generators are
consumed; their state afterwards is unspecified.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from emogen.errors import SelectionError, ShapeError
from emogen.ga.classical import ranked_pairs
from emogen.ga.step import (
    CROSSOVER_MUTATION,
    ELITE,
    KEPT,
    MEAN_ALL,
    MEAN_ELITE_OTHER,
    RANDOM,
)

_LOW32 = np.uint64(0xFFFFFFFF)
_SHIFT32 = np.uint64(32)
_SHIFT11 = np.uint64(11)
_TWO_M53 = 1.0 / 9007199254740992.0


@dataclass(frozen=True)
class BatchOffspring:
    """New populations of R runs.

    genes : (R, N, K) float; parents : (R, N, 2) int, indices into each run's previous
    population (-1 for none); operators : (N,) str, the same for every run of the batch.
    """

    genes: np.ndarray
    parents: np.ndarray
    operators: np.ndarray


# ---- the tape: where each draw sits in a fresh PCG64's raw stream ------------------------------
class _Tape:
    def __init__(self) -> None:
        self.n_raw = 0
        self._buffered: int | None = None  # raw whose high 32 bits wait for the next u32 draw

    def doubles(self, n: int) -> np.ndarray:
        pos = np.arange(self.n_raw, self.n_raw + n)
        self.n_raw += n
        return pos

    def bounded(self, k: int, n: int) -> tuple[int, np.ndarray, np.ndarray]:
        """n integers in [0, k) (Lemire on 32-bit draws; k == 1 draws nothing)."""
        pos, half = np.zeros(n, np.int64), np.zeros(n, np.int64)
        if k > 1:
            for i in range(n):
                if self._buffered is not None:
                    pos[i], half[i], self._buffered = self._buffered, 1, None
                else:
                    pos[i], half[i], self._buffered = self.n_raw, 0, self.n_raw
                    self.n_raw += 1
        return k, pos, half


def _doubles(raws: np.ndarray, pos: np.ndarray) -> np.ndarray:
    return (raws[:, pos] >> _SHIFT11).astype(np.float64) * _TWO_M53


def _bounded(raws: np.ndarray, spec: tuple[int, np.ndarray, np.ndarray]) -> tuple[Any, Any]:
    """(values (R, n) int64, suspect (R,) bool: a draw that numpy might have rejected)."""
    k, pos, half = spec
    if k <= 1:
        return np.zeros((len(raws), len(pos)), np.int64), np.zeros(len(raws), bool)
    r = raws[:, pos]
    u32 = np.where(half.astype(bool), r >> _SHIFT32, r & _LOW32)
    m = u32 * np.uint64(k)
    suspect = ((m & _LOW32) < np.uint64(k)).any(axis=1)
    return (m >> _SHIFT32).astype(np.int64), suspect


# ---- draw operations, in the one-run functions' order -------------------------------------------
class _Op:
    """One group of draws. ``public`` draws one run's values through the generator's methods;
    ``emulate`` reads every run's values off its raw stream. Both return a tuple of arrays
    (leading axis R for ``emulate``)."""

    def public(self, rng: np.random.Generator) -> tuple[np.ndarray, ...]:
        raise NotImplementedError

    def emulate(self, raws: np.ndarray) -> tuple[tuple[np.ndarray, ...], np.ndarray]:
        raise NotImplementedError


class _Partner(_Op):
    """Slot 3's other parent: ``rng.integers(len(others))``."""

    def __init__(self, tape: _Tape, n_others: int) -> None:
        self.n_others = n_others
        self.spec = tape.bounded(n_others, 1)

    def public(self, rng: np.random.Generator) -> tuple[np.ndarray, ...]:
        return (np.array([rng.integers(self.n_others)]),)

    def emulate(self, raws: np.ndarray) -> tuple[tuple[np.ndarray, ...], np.ndarray]:
        v, bad = _bounded(raws, self.spec)
        return (v,), bad


class _Mutation:
    """``mutate(child, m)`` of ``rows`` children: integers(0, K, (rows, m)), random((rows, m))."""

    def __init__(self, tape: _Tape, n_genes: int, m: int, rows: int) -> None:
        self.shape = (rows, m)
        self.n_genes = n_genes
        self.active = m > 0 and n_genes > 0
        if self.active:
            self.index = tape.bounded(n_genes, rows * m)
            self.values = tape.doubles(rows * m)

    def public(self, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        if not self.active:
            return np.zeros(self.shape, np.int64), np.zeros(self.shape)
        return rng.integers(0, self.n_genes, size=self.shape), rng.random(self.shape)

    def emulate(self, raws: np.ndarray) -> tuple[tuple[np.ndarray, np.ndarray], np.ndarray]:
        r = len(raws)
        if not self.active:
            z = (r, *self.shape)
            return (np.zeros(z, np.int64), np.zeros(z)), np.zeros(r, bool)
        idx, bad = _bounded(raws, self.index)
        vals = _doubles(raws, self.values)
        return (idx.reshape(r, *self.shape), vals.reshape(r, *self.shape)), bad


class _Crossover(_Op):
    """A crossover slot: ``choice(s, 2, replace=False)``, the mask, the mutation (s >= 2);
    only the mutation of the elite's copy when s == 1."""

    def __init__(self, tape: _Tape, s: int, n_genes: int, m: int) -> None:
        self.s, self.n_genes = s, n_genes
        if s >= 2:
            # Floyd's algorithm for 2 of s, then a shuffle of the two (numpy's choice).
            self.floyd = (tape.bounded(s - 1, 1), tape.bounded(s, 1), tape.bounded(2, 1))
            self.mask = tape.doubles(n_genes)
        self.mutation = _Mutation(tape, n_genes, m, 1)

    def public(self, rng: np.random.Generator) -> tuple[np.ndarray, ...]:
        if self.s >= 2:
            pair = rng.choice(self.s, size=2, replace=False)
            take_b = rng.random((1, self.n_genes))[0] < 0.5
        else:
            pair, take_b = np.zeros(2, np.int64), np.zeros(self.n_genes, bool)
        return (pair, take_b, *self.mutation.public(rng))

    def emulate(self, raws: np.ndarray) -> tuple[tuple[np.ndarray, ...], np.ndarray]:
        r = len(raws)
        (idx, mval), bad = self.mutation.emulate(raws)
        if self.s < 2:
            return (np.zeros((r, 2), np.int64), np.zeros((r, self.n_genes), bool), idx, mval), bad
        (v0, b0), (v1, b1), (sw, b2) = (_bounded(raws, f) for f in self.floyd)
        v0, v1, sw = v0[:, 0], v1[:, 0], sw[:, 0]
        v1 = np.where(v1 == v0, self.s - 1, v1)
        pair = np.where((sw == 0)[:, None], np.stack([v1, v0], 1), np.stack([v0, v1], 1))
        take_b = _doubles(raws, self.mask) < 0.5
        return (pair, take_b, idx, mval), bad | b0 | b1 | b2


class _ClassicalPair(_Op):
    """A classical pair: ``crossover_pair`` mask, then ``mutate`` of both children."""

    def __init__(self, tape: _Tape, n_genes: int, m: int) -> None:
        self.n_genes = n_genes
        self.mask = tape.doubles(n_genes)
        self.mutation = _Mutation(tape, n_genes, m, 2)

    def public(self, rng: np.random.Generator) -> tuple[np.ndarray, ...]:
        take_b = rng.random((1, self.n_genes))[0] < 0.5
        return (take_b, *self.mutation.public(rng))

    def emulate(self, raws: np.ndarray) -> tuple[tuple[np.ndarray, ...], np.ndarray]:
        (idx, mval), bad = self.mutation.emulate(raws)
        return (_doubles(raws, self.mask) < 0.5, idx, mval), bad


class _Random(_Op):
    """``random_faces(n, K, x)``: integers(0, K, (n, x)), random((n, x))."""

    def __init__(self, tape: _Tape, n: int, n_genes: int, x: int) -> None:
        self.shape = (n, x)
        self.n_genes = n_genes
        self.active = n > 0 and n_genes > 0 and x > 0
        if self.active:
            self.index = tape.bounded(n_genes, n * x)
            self.values = tape.doubles(n * x)

    def public(self, rng: np.random.Generator) -> tuple[np.ndarray, ...]:
        if not self.active:
            return np.zeros(self.shape, np.int64), np.zeros(self.shape)
        return rng.integers(0, self.n_genes, size=self.shape), rng.random(self.shape)

    def emulate(self, raws: np.ndarray) -> tuple[tuple[np.ndarray, ...], np.ndarray]:
        r = len(raws)
        if not self.active:
            z = (r, *self.shape)
            return (np.zeros(z, np.int64), np.zeros(z)), np.zeros(r, bool)
        idx, bad = _bounded(raws, self.index)
        vals = _doubles(raws, self.values)
        return (idx.reshape(r, *self.shape), vals.reshape(r, *self.shape)), bad


# ---- plans -----------------------------------------------------------------------------------
@dataclass(frozen=True)
class _Plan:
    slots: tuple[str, ...]  # kind of each bred slot: elite, mean_all, partner, kept, cx, pair
    ops: tuple[_Op, ...]  # the draws, in order (random faces last)
    n_raw: int
    n_random: int


@functools.lru_cache(maxsize=256)
def _emogen_plan(n: int, k: int, s: int, generation: int, n_random: int, m: int, x: int) -> _Plan:
    tape, slots, ops = _Tape(), [], list[_Op]()
    for slot in range(1, n - n_random + 1):
        if slot == 1:
            slots.append(ELITE)
        elif slot == 2 and s > 2:
            slots.append(MEAN_ALL)
        elif slot == 3 and generation not in (1, 2):
            if s >= 2:
                slots.append(MEAN_ELITE_OTHER)
                ops.append(_Partner(tape, s - 1))
            else:
                slots.append(KEPT)
        else:
            slots.append(CROSSOVER_MUTATION)
            ops.append(_Crossover(tape, s, k, m))
    ops.append(_Random(tape, n_random, k, x))
    return _Plan(tuple(slots), tuple(ops), tape.n_raw, n_random)


@functools.lru_cache(maxsize=256)
def _classical_plan(n: int, k: int, n_ranked: int, n_random: int, m: int, x: int) -> _Plan:
    tape, slots, ops = _Tape(), [ELITE], list[_Op]()
    n_bred, filled = n - n_random, 1
    pairs = ranked_pairs(n_ranked)
    while filled < n_bred:
        if next(pairs, None) is None:
            break
        ops.append(_ClassicalPair(tape, k, m))
        take = min(2, n_bred - filled)
        slots += [CROSSOVER_MUTATION] * take
        filled += take
    ops.append(_Random(tape, n - filled, k, x))
    return _Plan(tuple(slots), tuple(ops), tape.n_raw, n - filled)


# ---- drawing ---------------------------------------------------------------------------------
def _draw_public(plan: _Plan, rngs: Sequence[np.random.Generator]) -> list[tuple[np.ndarray, ...]]:
    per_run = [[op.public(rng) for op in plan.ops] for rng in rngs]
    return [
        tuple(np.stack([run[i][j] for run in per_run]) for j in range(len(per_run[0][i])))
        for i in range(len(plan.ops))
    ]


def _fresh_pcg64(rng: np.random.Generator) -> Any:
    """The state of a fresh PCG64 generator (no buffered 32-bit half), else None."""
    bg = rng.bit_generator
    if not isinstance(bg, np.random.PCG64):
        return None
    state: Any = bg.state
    return state if not state["has_uint32"] else None


def _draw(
    plan: _Plan, rngs: Sequence[np.random.Generator], *, emulate: bool | None = None
) -> list[tuple[np.ndarray, ...]]:
    """Every run's draws for the plan, stacked per op (leading axis R)."""
    if emulate is None:
        emulate = emulation_available()
    states = [_fresh_pcg64(rng) for rng in rngs] if emulate else []
    if not emulate or any(s is None for s in states) or plan.n_raw == 0:
        return _draw_public(plan, rngs)
    raws = np.stack([rng.bit_generator.random_raw(plan.n_raw) for rng in rngs])
    draws, suspect = [], np.zeros(len(rngs), bool)
    for op in plan.ops:
        values, bad = op.emulate(raws)
        draws.append(values)
        suspect |= bad
    for r in np.flatnonzero(suspect).tolist():  # redo through numpy itself (rejection sampling)
        rngs[r].bit_generator.state = states[r]
        for i, values in enumerate(_draw_public(plan, [rngs[r]])):
            for j, v in enumerate(values):
                draws[i][j][r] = v[0]
    return draws


@functools.cache
def emulation_available() -> bool:
    """Whether the raw-stream emulation reproduces this numpy's draws (checked once)."""
    from emogen.rng import generation_rng

    plans = [
        _emogen_plan(10, 30, 4, 3, 4, 2, 6),
        _emogen_plan(10, 30, 2, 0, 4, 2, 6),
        _emogen_plan(10, 7, 1, 4, 4, 3, 6),
        _emogen_plan(10, 30, 10, 1, 4, 2, 6),
        _classical_plan(10, 30, 10, 4, 2, 6),
    ]
    for plan in plans:
        fast = _draw(plan, [generation_rng(s, 0, 1) for s in range(24)], emulate=True)
        slow = _draw_public(plan, [generation_rng(s, 0, 1) for s in range(24)])
        for a, b in zip(fast, slow, strict=True):
            if not all(np.array_equal(x, y) for x, y in zip(a, b, strict=True)):
                return False
    return True


# ---- applying the operators, vectorised over runs ----------------------------------------------
def _check(genes: np.ndarray, rngs: Sequence[np.random.Generator]) -> np.ndarray:
    genes = np.asarray(genes, dtype=np.float64)
    if genes.ndim != 3:
        raise ShapeError(f"genes must have shape (n_runs, n_faces, n_genes); got {genes.shape}")
    if len(rngs) != genes.shape[0]:
        raise ShapeError(f"need one generator per run ({genes.shape[0]}); got {len(rngs)}")
    return genes


def _mutate(children: np.ndarray, index: np.ndarray, values: np.ndarray) -> None:
    """In place, like :func:`~emogen.ga.operators.mutate`: children (M, K), index/values (M, m)."""
    if index.size:
        rows = np.repeat(np.arange(len(children)), index.shape[1])
        children[rows, index.reshape(-1)] = values.reshape(-1)


def _random_faces(r: int, n: int, k: int, index: np.ndarray, values: np.ndarray) -> np.ndarray:
    """(R, n, K) random faces from index/values (R, n, x), like random_faces run by run."""
    flat = np.zeros((r * n, k))
    if n and k:
        _mutate(flat, index.reshape(r * n, -1), values.reshape(r * n, -1))
    return flat.reshape(r, n, k)


def next_generation_batch(
    genes: np.ndarray,
    elite: np.ndarray,
    others: np.ndarray,
    generation: int,
    *,
    rngs: Sequence[np.random.Generator],
    random_faces_count: int = 4,
    mutation_genes: int = 2,
    random_genes: int = 6,
) -> BatchOffspring:
    """P_{g+1} of R runs at once (Algorithm 1; see :func:`~emogen.ga.step.next_generation`).

    genes : (R, N, K) float; elite : (R,) int; others : (R, s − 1) int, indices into each run's
    population; ``rngs`` one generator per run. Run r's result equals
    ``next_generation(genes[r], elite[r], others[r], generation, rng=rngs[r])`` exactly.
    """
    genes = _check(genes, rngs)
    r, n, k = genes.shape
    elite = np.asarray(elite, dtype=np.int64).reshape(r)
    others = np.asarray(others, dtype=np.int64).reshape(r, -1)
    selected = np.concatenate([elite[:, None], others], axis=1)
    if selected.size and (selected.min() < 0 or selected.max() >= n):
        raise SelectionError(f"selection indices must be in [0, {n})")
    s = selected.shape[1]
    plan = _emogen_plan(n, k, s, int(generation), random_faces_count, mutation_genes, random_genes)
    draws = iter(_draw(plan, rngs))
    runs = np.arange(r)
    out = np.zeros_like(genes)
    parents = np.full((r, n, 2), -1, dtype=np.int64)
    elite_genes = genes[runs, elite]
    for i, kind in enumerate(plan.slots):
        if kind == ELITE:
            out[:, i], parents[:, i, 0] = elite_genes, elite
        elif kind == MEAN_ALL:
            out[:, i] = genes[runs[:, None], selected].mean(axis=1)
        elif kind == MEAN_ELITE_OTHER:
            (partner,) = next(draws)
            other = others[runs, partner[:, 0]]
            out[:, i] = (elite_genes + genes[runs, other]) / 2
            parents[:, i, 0], parents[:, i, 1] = elite, other
        elif kind == KEPT:
            out[:, i], parents[:, i, 0] = genes[:, i], i
        else:
            pair, take_b, index, values = next(draws)
            if s >= 2:
                a, b = selected[runs, pair[:, 0]], selected[runs, pair[:, 1]]
                child = np.where(take_b, genes[runs, b], genes[runs, a])
                parents[:, i, 0], parents[:, i, 1] = a, b
            else:
                child = elite_genes.copy()
                parents[:, i, 0] = elite
            _mutate(child, index[:, 0], values[:, 0])
            out[:, i] = child
    index, values = next(draws)
    out[:, len(plan.slots) :] = _random_faces(r, plan.n_random, k, index, values)
    ops = np.array([*plan.slots, *[RANDOM] * plan.n_random])
    return BatchOffspring(out, parents, ops)


def classical_next_generation_batch(
    genes: np.ndarray,
    ranking: np.ndarray,
    *,
    rngs: Sequence[np.random.Generator],
    random_faces_count: int = 4,
    mutation_genes: int = 2,
    random_genes: int = 6,
) -> BatchOffspring:
    """The classical variant for R runs: ranking (R, L) int, best first, L equal for all runs.

    Run r's result equals ``classical_next_generation(genes[r], ranking[r], rng=rngs[r])``.
    """
    genes = _check(genes, rngs)
    r, n, k = genes.shape
    ranking = np.asarray(ranking, dtype=np.int64).reshape(r, -1)
    if ranking.shape[1] == 0 or ranking.min() < 0 or ranking.max() >= n:
        raise SelectionError(f"ranking must hold indices in [0, {n})")
    plan = _classical_plan(n, k, ranking.shape[1], random_faces_count, mutation_genes, random_genes)
    draws = iter(_draw(plan, rngs))
    runs = np.arange(r)
    out = np.zeros_like(genes)
    parents = np.full((r, n, 2), -1, dtype=np.int64)
    out[:, 0], parents[:, 0, 0] = genes[runs, ranking[:, 0]], ranking[:, 0]
    slot = 1
    pairs = ranked_pairs(ranking.shape[1])
    for _ in plan.ops[:-1]:
        take_b, index, values = next(draws)
        pi, pj = next(pairs)
        a, b = ranking[:, pi], ranking[:, pj]
        ga, gb = genes[runs, a], genes[runs, b]
        children = np.stack([np.where(take_b, gb, ga), np.where(take_b, ga, gb)], axis=1)
        flat = children.reshape(2 * r, k)
        _mutate(flat, index.reshape(2 * r, -1), values.reshape(2 * r, -1))
        for c in range(min(2, n - plan.n_random - slot)):
            out[:, slot] = flat.reshape(r, 2, k)[:, c]
            parents[:, slot, 0], parents[:, slot, 1] = a, b
            slot += 1
    index, values = next(draws)
    out[:, slot:] = _random_faces(r, plan.n_random, k, index, values)
    ops = np.array([*plan.slots, *[RANDOM] * plan.n_random])
    return BatchOffspring(out, parents, ops)
