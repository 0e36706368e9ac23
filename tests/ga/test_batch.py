"""The batched GA step equals the one-run step exactly, run by run, for the same generators."""

from __future__ import annotations

import numpy as np
import pytest

import emogen.ga.batch as batch
from emogen.errors import SelectionError, ShapeError
from emogen.ga.batch import (
    classical_next_generation_batch,
    emulation_available,
    next_generation_batch,
)
from emogen.ga.classical import classical_next_generation
from emogen.ga.step import next_generation
from emogen.rng import generation_rng

SHAPES = [  # (N, K, random faces, m, x)
    (10, 30, 4, 2, 6),
    (10, 24, 4, 2, 6),
    (6, 5, 2, 3, 2),
    (10, 1, 3, 2, 6),
    (10, 30, 0, 0, 6),
    (5, 3, 1, 1, 1),
]
RUNS = 12


def same(offspring, r: int, ref) -> bool:
    return (
        np.array_equal(offspring.genes[r], ref.genes)
        and np.array_equal(offspring.parents[r], ref.parents)
        and np.array_equal(offspring.operators, ref.operators)
    )


def rngs(seeds, g: int) -> list[np.random.Generator]:
    return [generation_rng(int(s), 0, g) for s in seeds]


@pytest.mark.parametrize(("n", "k", "n_random", "m", "x"), SHAPES)
def test_batch_equals_next_generation_run_by_run(n, k, n_random, m, x) -> None:
    data = np.random.default_rng(n * 100 + k)
    params = {"random_faces_count": n_random, "mutation_genes": m, "random_genes": x}
    for s in range(1, n + 1):
        for g in range(5):  # slot 3 behaves differently in generations 1 and 2
            genes = data.random((RUNS, n, k))
            sel = np.array([data.permutation(n)[:s] for _ in range(RUNS)])
            seeds = data.integers(0, 2**62, RUNS)
            off = next_generation_batch(
                genes, sel[:, 0], sel[:, 1:], g, rngs=rngs(seeds, g + 1), **params
            )
            for r in range(RUNS):
                ref = next_generation(
                    genes[r],
                    sel[r, 0],
                    sel[r, 1:],
                    g,
                    rng=generation_rng(int(seeds[r]), 0, g + 1),
                    **params,
                )
                assert same(off, r, ref), (s, g, r)


@pytest.mark.parametrize(("n", "k", "n_random", "m", "x"), SHAPES)
def test_classical_batch_equals_the_one_run_variant(n, k, n_random, m, x) -> None:
    data = np.random.default_rng(k)
    params = {"random_faces_count": n_random, "mutation_genes": m, "random_genes": x}
    for length in range(1, n + 1):
        genes = data.random((RUNS, n, k))
        ranking = np.array([data.permutation(n)[:length] for _ in range(RUNS)])
        seeds = data.integers(0, 2**62, RUNS)
        off = classical_next_generation_batch(genes, ranking, rngs=rngs(seeds, 1), **params)
        for r in range(RUNS):
            ref = classical_next_generation(
                genes[r], ranking[r], rng=generation_rng(int(seeds[r]), 0, 1), **params
            )
            assert same(off, r, ref), (length, r)


def test_emulation_is_checked_and_the_public_path_agrees() -> None:
    assert emulation_available()  # numpy draws as emulated in this environment
    plan = batch._emogen_plan(10, 30, 4, 3, 4, 2, 6)
    seeds = range(40)
    fast = batch._draw(plan, rngs(seeds, 1), emulate=True)
    slow = batch._draw(plan, rngs(seeds, 1), emulate=False)
    for a, b in zip(fast, slow, strict=True):
        for x, y in zip(a, b, strict=True):
            np.testing.assert_array_equal(x, y)


def test_runs_flagged_for_rejection_are_redone_through_numpy(monkeypatch) -> None:
    """A Lemire draw that numpy might reject sends its run to the public path: same result."""
    real = batch._bounded

    def every_run_suspect(raws, spec):
        values, _ = real(raws, spec)
        return values, np.ones(len(raws), bool)

    data = np.random.default_rng(9)
    genes = data.random((6, 10, 30))
    sel = np.array([data.permutation(10)[:4] for _ in range(6)])
    expected = next_generation_batch(genes, sel[:, 0], sel[:, 1:], 3, rngs=rngs(range(6), 4))
    monkeypatch.setattr(batch, "_bounded", every_run_suspect)
    redone = next_generation_batch(genes, sel[:, 0], sel[:, 1:], 3, rngs=rngs(range(6), 4))
    np.testing.assert_array_equal(redone.genes, expected.genes)


def test_other_generators_take_the_public_path() -> None:
    data = np.random.default_rng(10)
    genes = data.random((3, 10, 30))
    sel = np.array([data.permutation(10)[:3] for _ in range(3)])
    mt = [np.random.Generator(np.random.MT19937(s)) for s in range(3)]
    off = next_generation_batch(genes, sel[:, 0], sel[:, 1:], 0, rngs=mt)
    for r in range(3):
        ref = next_generation(
            genes[r], sel[r, 0], sel[r, 1:], 0, rng=np.random.Generator(np.random.MT19937(r))
        )
        assert same(off, r, ref)


def test_errors() -> None:
    genes = np.zeros((2, 10, 5))
    with pytest.raises(ShapeError, match="one generator per run"):
        next_generation_batch(genes, [0, 0], [[1], [1]], 0, rngs=rngs([1], 1))
    with pytest.raises(ShapeError, match=r"\(n_runs, n_faces, n_genes\)"):
        next_generation_batch(genes[0], [0], [[1]], 0, rngs=rngs([1], 1))
    with pytest.raises(SelectionError, match="must be in"):
        next_generation_batch(genes, [0, 10], [[1], [1]], 0, rngs=rngs([1, 2], 1))
    with pytest.raises(SelectionError, match="ranking"):
        classical_next_generation_batch(genes, [[0, 12], [1, 2]], rngs=rngs([1, 2], 1))
