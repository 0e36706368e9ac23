"""Algorithm 1: which operator fills which slot, and what each slot holds (both streams)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from emogen.errors import SelectionError
from emogen.ga.algorithm import Offspring, next_generation
from emogen.ga.draws import BlockDraws, LegacyDraws

CM, RND = "crossover_mutation", "random"


def population(n: int = 10, k: int = 24, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    genes = rng.random((n, k))
    genes[rng.random((n, k)) < 0.6] = 0.0
    return genes


def one_run(off: Offspring) -> Offspring:
    return Offspring(off.genes[0], off.parents[0], off.operators)


@pytest.fixture(params=[1, 2], ids=["stream1", "stream2"])
def stream(request: pytest.FixtureRequest) -> int:
    return int(request.param)


def draws_of(rng: np.random.Generator, stream: int = 2):  # type: ignore[no-untyped-def]
    return LegacyDraws([rng]) if stream == 1 else BlockDraws([rng], 16)


def step(genes, elite, others, g, seed=1, stream=2, **kw):  # type: ignore[no-untyped-def]
    """One run (a batch of one), as the engine calls it."""
    off = next_generation(
        genes[None],
        np.array([elite]),
        np.array(others, dtype=int)[None],
        g,
        draws=draws_of(np.random.default_rng(seed), stream),
        **kw,
    )
    return one_run(off)


@pytest.mark.parametrize(
    ("others", "g", "expected"),
    [
        # only the elite: slot 2 falls through to crossover, slot 3 keeps the old slot-3 face
        ([], 0, ["elite", CM, "kept", CM, CM, CM]),
        # two selections: slot 2 (needs S > 2) falls through; slot 3 averages elite + other
        ([4], 0, ["elite", CM, "mean_elite_other", CM, CM, CM]),
        ([4, 7], 0, ["elite", "mean_all", "mean_elite_other", CM, CM, CM]),
        # generations 1 and 2: slot 3 falls through to crossover
        ([4, 7], 1, ["elite", "mean_all", CM, CM, CM, CM]),
        ([4, 7, 8, 9], 2, ["elite", "mean_all", CM, CM, CM, CM]),
        ([4, 7, 8, 9], 3, ["elite", "mean_all", "mean_elite_other", CM, CM, CM]),
        ([], 1, ["elite", CM, CM, CM, CM, CM]),
    ],
)
def test_slots_follow_algorithm_1(others, g, expected, stream) -> None:
    off = step(population(), 2, others, g, stream=stream)
    assert off.operators.tolist() == [*expected, RND, RND, RND, RND]


def test_slot_contents(stream) -> None:
    genes = population()
    elite, others = 2, np.array([4, 7, 8])
    selected = [elite, *others.tolist()]
    for seed in range(20):
        off = step(genes, elite, others, 0, seed=seed, stream=stream)
        np.testing.assert_array_equal(off.genes[0], genes[elite])
        assert off.parents[0].tolist() == [elite, -1]
        np.testing.assert_allclose(off.genes[1], genes[selected].mean(0))
        assert off.parents[1].tolist() == [-1, -1]
        e, other = off.parents[2]
        assert e == elite and other in others
        np.testing.assert_allclose(off.genes[2], (genes[elite] + genes[other]) / 2)
        for i in range(3, 6):
            a, b = off.parents[i]
            assert a != b and {a, b} <= set(selected)
            from_parent = (off.genes[i] == genes[a]) | (off.genes[i] == genes[b])
            assert (~from_parent).sum() <= 2  # m = 2 mutated genes at most
        for face in off.genes[6:]:
            assert (face > 0).sum() <= 6
        assert np.all(off.parents[6:] == -1)


def test_kept_slot_copies_the_current_slot_3_face() -> None:
    genes = population()
    off = step(genes, 5, [], 4)
    np.testing.assert_array_equal(off.genes[2], genes[2])
    assert off.parents[2].tolist() == [2, -1]


def test_elite_only_crossover_is_a_mutated_elite_copy() -> None:
    genes = population()
    off = step(genes, 5, [], 1, mutation_genes=2)
    for i in range(1, 6):
        assert off.operators[i] == CM and off.parents[i].tolist() == [5, -1]
        assert (off.genes[i] != genes[5]).sum() <= 2
    off0 = step(genes, 5, [], 1, mutation_genes=0)
    np.testing.assert_array_equal(off0.genes[1:6], np.repeat(genes[[5]], 5, axis=0))


def test_pairs_are_drawn_uniformly_from_the_selection(stream) -> None:
    genes = population(k=30)
    counts: dict[tuple[int, int], int] = {}
    for seed in range(400):
        off = step(genes, 0, [1, 2], 5, seed=seed, stream=stream)
        for a, b in off.parents[3:6]:
            key = (min(a, b), max(a, b))
            counts[key] = counts.get(key, 0) + 1
    assert set(counts) == {(0, 1), (0, 2), (1, 2)}
    from scipy import stats

    assert stats.chisquare(list(counts.values())).pvalue > 0.01


@settings(max_examples=40, deadline=None)
@given(
    n=st.integers(2, 14),
    boost=st.integers(0, 13),
    m=st.integers(0, 4),
    x=st.integers(1, 8),
    g=st.integers(0, 12),
    n_sel=st.integers(1, 14),
    seed=st.integers(0, 2**32 - 1),
)
def test_configurable_sizes(n, boost, m, x, g, n_sel, seed) -> None:
    boost = min(boost, n - 1)
    n_sel = min(n_sel, n)
    genes = population(n=n, k=12, seed=seed % 100)
    rng = np.random.default_rng(seed)
    chosen = rng.permutation(n)[:n_sel]
    off = step(
        genes,
        int(chosen[0]),
        chosen[1:],
        g,
        seed=seed,
        stream=1 + seed % 2,
        random_faces_count=boost,
        mutation_genes=m,
        random_genes=x,
    )
    assert off.genes.shape == genes.shape and off.parents.shape == (n, 2)
    assert off.operators[0] == "elite"
    assert (off.operators == RND).sum() == boost
    assert np.all((off.genes >= 0) & (off.genes <= 1))
    assert np.all((off.genes[off.operators == RND] > 0).sum(1) <= x)


def test_bad_indices_are_rejected() -> None:
    with pytest.raises(
        SelectionError, match=r"selection indices must be in \[0, 10\); got \[\[12\]\]"
    ):
        step(population(), 12, [], 0)
    with pytest.raises(SelectionError, match=r"run 0 has \[3, 3\]"):
        step(population(), 3, [3], 0)
