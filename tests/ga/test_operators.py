"""The GA operators S, B, M, A, R: properties (hypothesis) and distributions (scipy.stats).

B, M, R run over a leading run axis with their numbers from a Draws; the helpers below give each
test's rows their own generators, on stream 1 or 2 (by the seed's parity), so both streams'
draws are checked for the operators' distributions.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy import stats

from emogen.errors import SelectionError, ShapeError
from emogen.ga import operators as ops
from emogen.ga.draws import BlockDraws, Draws, LegacyDraws
from emogen.ga.operators import select


def draws_for(rng: np.random.Generator, runs: int) -> Draws:
    gens = rng.spawn(runs)
    return LegacyDraws(gens) if int(rng.integers(2)) else BlockDraws(gens, 4)


def crossover(a: np.ndarray, b: np.ndarray, *, rng: np.random.Generator) -> np.ndarray:
    """Row i of a with row i of b, each row a run."""
    return ops.crossover(a, b, draws_for(rng, len(a)))


def crossover_pair(a, b, *, rng):  # type: ignore[no-untyped-def]
    children = ops.crossover_pair(a, b, draws_for(rng, len(a)))
    return children[:, 0], children[:, 1]


def mutate(genes: np.ndarray, m: int, *, rng: np.random.Generator) -> np.ndarray:
    """The faces of one run."""
    return ops.mutate(np.asarray(genes)[None], m, draws_for(rng, 1))[0]


def average(members: np.ndarray) -> np.ndarray:
    return ops.average(np.asarray(members)[None])[0]


def random_faces(n: int, k: int, x: int, *, rng: np.random.Generator) -> np.ndarray:
    return ops.random_faces(n, k, x, draws_for(rng, 1))[0]


unit = st.floats(0, 1, allow_nan=False)
seeds = st.integers(0, 2**32 - 1)


@st.composite
def gene_pairs(draw: st.DrawFn) -> tuple[np.ndarray, np.ndarray]:
    n = draw(st.integers(1, 6))
    k = draw(st.integers(1, 40))
    a = draw(arrays(np.float64, (n, k), elements=unit))
    b = draw(arrays(np.float64, (n, k), elements=unit))
    return a, b


# ---- B ---------------------------------------------------------------------------------------
@settings(max_examples=60, deadline=None)
@given(pair=gene_pairs(), seed=seeds)
def test_crossover_child_takes_every_gene_from_one_parent(pair, seed) -> None:
    a, b = pair
    child = crossover(a, b, rng=np.random.default_rng(seed))
    assert child.shape == a.shape
    assert np.all((child == a) | (child == b))


@settings(max_examples=40, deadline=None)
@given(pair=gene_pairs(), seed=seeds)
def test_crossover_pair_children_are_complementary(pair, seed) -> None:
    a, b = pair
    c1, c2 = crossover_pair(a, b, rng=np.random.default_rng(seed))
    assert np.all(((c1 == a) & (c2 == b)) | ((c1 == b) & (c2 == a)))


def test_crossover_takes_each_gene_from_either_parent_with_probability_half() -> None:
    n, k = 4000, 30
    child = crossover(np.zeros((n, k)), np.ones((n, k)), rng=np.random.default_rng(12345))
    from_b = int(child.sum())
    assert stats.binomtest(from_b, n * k, 0.5).pvalue > 0.01
    # and gene by gene (Bonferroni over the 30 genes)
    per_gene = child.sum(0).astype(int)
    pvalues = [stats.binomtest(int(c), n, 0.5).pvalue for c in per_gene]
    assert min(pvalues) > 0.01 / k


def test_crossover_rejects_mismatched_parents() -> None:
    with pytest.raises(
        ShapeError, match=r"both have shape \(n_runs, n_genes\); got \(1, 3\) and \(1, 4\)"
    ):
        crossover(np.zeros((1, 3)), np.zeros((1, 4)), rng=np.random.default_rng(0))


# ---- M ---------------------------------------------------------------------------------------
@settings(max_examples=60, deadline=None)
@given(
    genes=st.integers(1, 5).flatmap(
        lambda n: st.integers(1, 40).flatmap(lambda k: arrays(np.float64, (n, k), elements=unit))
    ),
    m=st.integers(0, 6),
    seed=seeds,
)
def test_mutation_changes_at_most_m_genes_and_stays_in_range(genes, m, seed) -> None:
    out = mutate(genes, m, rng=np.random.default_rng(seed))
    assert out.shape == genes.shape
    assert np.all((out != genes).sum(1) <= m)
    assert np.all((out >= 0) & (out <= 1))
    assert genes is not out


def test_mutation_values_are_uniform_on_the_unit_interval() -> None:
    sentinel = -1.0
    out = mutate(np.full((5000, 30), sentinel), 2, rng=np.random.default_rng(2024))
    values = out[out != sentinel]
    assert len(values) > 9000  # 2 per face, fewer only where an index was drawn twice
    assert stats.kstest(values, "uniform").pvalue > 0.01


def test_mutation_indices_are_uniform_over_genes() -> None:
    k = 30
    out = mutate(np.full((9000, k), -1.0), 1, rng=np.random.default_rng(99))
    changed = out != -1.0
    assert np.all(changed.sum(1) == 1)
    counts = changed.sum(0)
    assert stats.chisquare(counts).pvalue > 0.01
    # with m = 2 as well (duplicated draws are symmetric across genes)
    counts2 = (mutate(np.full((9000, k), -1.0), 2, rng=np.random.default_rng(98)) != -1.0).sum(0)
    assert stats.chisquare(counts2).pvalue > 0.01


def test_mutation_of_zero_genes_is_a_copy() -> None:
    genes = np.random.default_rng(0).random((3, 5))
    np.testing.assert_array_equal(mutate(genes, 0, rng=np.random.default_rng(1)), genes)


# ---- A ---------------------------------------------------------------------------------------
@settings(max_examples=60, deadline=None)
@given(
    members=st.integers(1, 8).flatmap(
        lambda s: st.integers(1, 40).flatmap(lambda k: arrays(np.float64, (s, k), elements=unit))
    )
)
def test_average_stays_within_the_parents_range(members) -> None:
    mean = average(members)
    assert mean.shape == (members.shape[1],)
    assert np.all(mean >= members.min(0) - 1e-12)
    assert np.all(mean <= members.max(0) + 1e-12)


def test_average_is_the_arithmetic_mean() -> None:
    np.testing.assert_allclose(average(np.array([[0.0, 1.0], [1.0, 0.5]])), [0.5, 0.75])
    with pytest.raises(ShapeError, match="at least one"):
        average(np.zeros((0, 3)))


# ---- R ---------------------------------------------------------------------------------------
@settings(max_examples=60, deadline=None)
@given(n=st.integers(0, 8), k=st.integers(1, 40), x=st.integers(0, 12), seed=seeds)
def test_random_faces_have_at_most_x_active_genes(n, k, x, seed) -> None:
    faces = random_faces(n, k, x, rng=np.random.default_rng(seed))
    assert faces.shape == (n, k)
    assert np.all((faces > 0).sum(1) <= x)
    assert np.all((faces >= 0) & (faces < 1))


def test_random_face_indices_and_values_are_uniform() -> None:
    faces = random_faces(6000, 30, 1, rng=np.random.default_rng(5))
    assert stats.chisquare((faces > 0).sum(0)).pvalue > 0.01
    assert stats.kstest(faces[faces > 0], "uniform").pvalue > 0.01


# ---- S ---------------------------------------------------------------------------------------
IDS = np.arange(100, 110)


def test_select_maps_ids_to_indices() -> None:
    e, o = select(IDS, 103, [101, 109])
    assert e == 3 and o.tolist() == [1, 9]
    e, o = select(IDS, [105])
    assert e == 5 and o.tolist() == []


@pytest.mark.parametrize(
    ("elite", "others", "kwargs", "match"),
    [
        ([], [], {}, "exactly one elite; got 0"),
        ([101, 102], [], {}, "exactly one elite; got 2"),
        ("101", [], {}, "elite must be a face id"),
        (1, [], {}, "elite 1 is not in the population"),
        (101, [102, 7], {}, r"selected face\(s\) \[7\] are not in the population"),
        (101, [101, 102], {}, "elite 101 must not also be among"),
        (101, [102, 102], {}, "must be distinct"),
        (101, [], {"min_selections": 2}, r"must be in \[2, 10\]; got 1"),
        (101, [102, 103, 104], {"max_selections": 3}, r"must be in \[1, 3\]; got 4"),
    ],
)
def test_select_rejects_bad_selections(elite, others, kwargs, match) -> None:
    with pytest.raises(SelectionError, match=match):
        select(IDS, elite, others, **kwargs)
