"""The classical GA variant: fitness-ranked pairs, each breeding once into two children."""

from __future__ import annotations

import numpy as np
import pytest

from emogen.errors import SelectionError
from emogen.ga.algorithm import Offspring, ranked_pairs
from emogen.ga.algorithm import classical_next_generation as batch_classical
from emogen.ga.draws import BlockDraws


def classical_next_generation(genes, ranking, *, rng, **kw) -> Offspring:  # type: ignore[no-untyped-def]
    """One run (a batch of one) from ``rng``'s stream-2 block."""
    off = batch_classical(genes[None], np.asarray(ranking)[None], draws=BlockDraws([rng], 8), **kw)
    return Offspring(off.genes[0], off.parents[0], off.operators)


def test_pairs_in_order_of_fitness_each_once() -> None:
    pairs = list(ranked_pairs(4))
    assert pairs == [(0, 1), (0, 2), (1, 2), (0, 3), (1, 3), (2, 3)]
    assert len(set(pairs)) == len(pairs)


def test_fittest_pairs_breed_two_complementary_children() -> None:
    rng = np.random.default_rng(3)
    genes = rng.random((10, 20))
    ranking = np.array([7, 2, 5, 0, 1, 3, 4, 6, 8, 9])
    off = classical_next_generation(genes, ranking, mutation_genes=0, rng=rng)
    assert off.operators.tolist() == ["elite"] + ["crossover_mutation"] * 5 + ["random"] * 4
    np.testing.assert_array_equal(off.genes[0], genes[7])
    # children of (7,2), (7,2), (7,5), (7,5), (2,5): the three fittest faces only
    assert [tuple(p) for p in off.parents[1:6]] == [(7, 2), (7, 2), (7, 5), (7, 5), (2, 5)]
    for i in (1, 3):
        a, b = off.parents[i]
        np.testing.assert_allclose(off.genes[i] + off.genes[i + 1], genes[a] + genes[b])
        assert np.all((off.genes[i] == genes[a]) | (off.genes[i] == genes[b]))


def test_children_are_mutated() -> None:
    rng = np.random.default_rng(4)
    genes = rng.random((10, 20))
    off = classical_next_generation(genes, np.arange(10), mutation_genes=2, rng=rng)
    for i in range(1, 6):
        a, b = off.parents[i]
        outside = ~((off.genes[i] == genes[a]) | (off.genes[i] == genes[b]))
        assert outside.sum() <= 2


def test_short_ranking_fills_with_random_faces() -> None:
    genes = np.random.default_rng(5).random((10, 20))
    off = classical_next_generation(genes, np.array([3, 4]), rng=np.random.default_rng(6))
    assert (
        off.operators.tolist()
        == ["elite", "crossover_mutation", "crossover_mutation"] + ["random"] * 7
    )


def test_bad_ranking() -> None:
    genes = np.zeros((10, 4))
    with pytest.raises(SelectionError, match="repeat"):
        classical_next_generation(genes, np.array([1, 1]), rng=np.random.default_rng(0))
    with pytest.raises(SelectionError, match="indices"):
        classical_next_generation(genes, np.array([10]), rng=np.random.default_rng(0))
