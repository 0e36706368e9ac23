"""The two GA streams: stream 2 against a plain per-run transcription of Algorithm 1, stream 1
against offspring recorded with the pre-redesign GA, and the draws' distributions."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from emogen.errors import ConfigError, SelectionError, ShapeError
from emogen.ga.algorithm import classical_next_generation, next_generation
from emogen.ga.draws import BlockDraws, LegacyDraws, block_size, check_stream, generation_draws
from emogen.rng import generation_rng

DATA = Path(__file__).parents[1] / "data"
SHAPES = [(10, 30, 4, 2, 6), (10, 24, 4, 2, 6), (6, 5, 2, 3, 2), (10, 1, 3, 2, 6), (5, 3, 1, 1, 1)]


class Uniforms:
    """A run's stream-2 doubles, read one at a time (the reference's draw source)."""

    def __init__(self, rng: np.random.Generator) -> None:
        self.values = rng.random(10_000).tolist()
        self.at = 0

    def u(self) -> float:
        self.at += 1
        return self.values[self.at - 1]

    def int(self, k: int) -> int:
        return int(self.u() * k)


def reference_emogen(genes, elite, others, g, src, n_random, m, x):  # type: ignore[no-untyped-def]
    """Algorithm 1 for one run with plain Python lists (see docs/ga.md for the reading)."""
    n, k = len(genes), len(genes[0])
    sel = [elite, *others]
    s = len(sel)
    out, parents, ops = [], [], []

    def mutated(child):  # type: ignore[no-untyped-def]
        child = list(child)
        if m and k:
            idx = [src.int(k) for _ in range(m)]
            val = [src.u() for _ in range(m)]
            for i, v in zip(idx, val, strict=True):
                child[i] = v
        return child

    for slot in range(1, n - n_random + 1):
        if slot == 1:
            out.append(list(genes[elite])), parents.append([elite, -1]), ops.append("elite")
        elif slot == 2 and s > 2:
            out.append([sum(genes[j][i] for j in sel) / s for i in range(k)])
            parents.append([-1, -1]), ops.append("mean_all")
        elif slot == 3 and g not in (1, 2):
            if s >= 2:
                o = others[src.int(s - 1)]
                out.append([(genes[elite][i] + genes[o][i]) / 2 for i in range(k)])
                parents.append([elite, o]), ops.append("mean_elite_other")
            else:
                out.append(list(genes[2])), parents.append([2, -1]), ops.append("kept")
        else:
            if s >= 2:
                a = int(src.u() * s)
                b = int(src.u() * (s - 1))
                b += b >= a
                a, b = sel[a], sel[b]
                mask = [src.u() < 0.5 for _ in range(k)]
                child = [genes[b][i] if mask[i] else genes[a][i] for i in range(k)]
                parents.append([a, b])
            else:
                child = list(genes[elite])
                parents.append([elite, -1])
            out.append(mutated(child)), ops.append("crossover_mutation")
    n_rand = n - len(out)
    if n_rand and k and x:
        idx = [[src.int(k) for _ in range(x)] for _ in range(n_rand)]
        val = [[src.u() for _ in range(x)] for _ in range(n_rand)]
    for f in range(n_rand):
        face = [0.0] * k
        if k and x:
            for i, v in zip(idx[f], val[f], strict=True):
                face[i] = v
        out.append(face), parents.append([-1, -1]), ops.append("random")
    return out, parents, ops


@pytest.mark.parametrize(("n", "k", "n_random", "m", "x"), SHAPES)
def test_stream_2_equals_a_plain_transcription_run_by_run(n, k, n_random, m, x) -> None:
    data = np.random.default_rng(n * 100 + k)
    params = {"random_faces_count": n_random, "mutation_genes": m, "random_genes": x}
    runs = 8
    for s in range(1, n + 1):
        for g in range(5):  # slot 3 behaves differently in generations 1 and 2
            genes = data.random((runs, n, k))
            sel = np.array([data.permutation(n)[:s] for _ in range(runs)])
            seeds = data.integers(0, 2**62, runs)
            draws = generation_draws(seeds, 0, g + 1, stream=2, block=block_size(n, k, m, x))
            off = next_generation(genes, sel[:, 0], sel[:, 1:], g, draws=draws, **params)
            for r in range(runs):
                src = Uniforms(generation_rng(int(seeds[r]), 0, g + 1))
                ref = reference_emogen(
                    genes[r].tolist(), int(sel[r, 0]), sel[r, 1:].tolist(), g, src, n_random, m, x
                )
                np.testing.assert_allclose(off.genes[r], ref[0], rtol=0, atol=1e-15)
                assert off.parents[r].tolist() == ref[1]
                assert off.operators.tolist() == ref[2]
                assert src.at <= block_size(n, k, m, x)


def _digest(genes: np.ndarray, parents: np.ndarray, ops: np.ndarray) -> str:
    h = hashlib.sha256()
    h.update(np.ascontiguousarray(genes, dtype="<f8").tobytes())
    h.update(np.ascontiguousarray(parents, dtype="<i8").tobytes())
    h.update("|".join(ops.tolist()).encode())
    return h.hexdigest()


def test_stream_1_reproduces_offspring_recorded_before_the_redesign() -> None:
    """Engines recorded with ``emogen.ga.engine/1`` continue exactly as they were drawn."""
    recorded = json.loads((DATA / "ga_stream1.json").read_text())
    assert len(recorded["cases"]) == 96
    for c in recorded["cases"]:
        data = np.random.default_rng([2026, c["case"]])
        n, k, s, g = c["n"], c["k"], c["s"], c["generation"]
        genes = data.random((n, k))
        sel = data.permutation(n)[:s]
        seed = int(data.integers(0, 2**62))
        p = {"random_faces_count": c["random_faces"], "mutation_genes": c["m"]}
        p["random_genes"] = c["x"]

        def legacy() -> LegacyDraws:
            return LegacyDraws([generation_rng(seed, 1, g + 1)])  # noqa: B023

        off = next_generation(genes[None], sel[:1], sel[None, 1:], g, draws=legacy(), **p)
        cl = classical_next_generation(genes[None], sel[None], draws=legacy(), **p)
        assert _digest(off.genes[0], off.parents[0], off.operators) == c["emogen"], c
        assert _digest(cl.genes[0], cl.parents[0], cl.operators) == c["classical"], c


def test_a_batch_equals_its_runs_one_at_a_time() -> None:
    data = np.random.default_rng(5)
    genes = data.random((30, 10, 12))
    sel = np.array([data.permutation(10)[:4] for _ in range(30)])
    seeds = data.integers(0, 2**62, 30)
    for stream in (1, 2):
        whole = next_generation(
            genes,
            sel[:, 0],
            sel[:, 1:],
            3,
            draws=generation_draws(seeds, 2, 4, stream=stream, block=block_size(10, 12, 2, 6)),
        )
        for r in (0, 7, 29):
            one = next_generation(
                genes[r : r + 1],
                sel[r : r + 1, 0],
                sel[r : r + 1, 1:],
                3,
                draws=generation_draws(
                    seeds[r : r + 1], 2, 4, stream=stream, block=block_size(10, 12, 2, 6)
                ),
            )
            np.testing.assert_array_equal(whole.genes[r], one.genes[0])
            np.testing.assert_array_equal(whole.parents[r], one.parents[0])


def test_block_integers_and_pairs_are_uniform() -> None:
    draws = BlockDraws([np.random.default_rng(s) for s in range(4000)], 10)
    ints = draws.integers(7, (5,)).reshape(-1)
    assert ints.min() == 0 and ints.max() == 6
    assert stats.chisquare(np.bincount(ints, minlength=7)).pvalue > 0.001
    pairs = draws.pairs(4)
    assert np.all(pairs[:, 0] != pairs[:, 1])
    counts = np.bincount(pairs[:, 0] * 4 + pairs[:, 1], minlength=16)
    ordered = counts[[i * 4 + j for i in range(4) for j in range(4) if i != j]]
    assert counts.sum() == ordered.sum() == 4000
    assert stats.chisquare(ordered).pvalue > 0.001


def test_block_continues_each_runs_sequence_past_its_end() -> None:
    draws = BlockDraws([np.random.default_rng(1), np.random.default_rng(2)], 3)
    got = draws.uniforms((8,))
    for r, seed in enumerate((1, 2)):
        np.testing.assert_array_equal(got[r], np.random.default_rng(seed).random(8))


def test_legacy_draws_are_the_generators_own_calls() -> None:
    draws = LegacyDraws([np.random.default_rng(3)])
    ref = np.random.default_rng(3)
    assert draws.integers(5, ())[0] == ref.integers(5)
    np.testing.assert_array_equal(draws.pairs(6)[0], ref.choice(6, size=2, replace=False))
    np.testing.assert_array_equal(draws.uniforms((2, 3))[0], ref.random((2, 3)))


def test_errors_name_the_bad_value() -> None:
    with pytest.raises(ConfigError, match=r"GA stream must be one of \[1, 2\]; got 3"):
        check_stream(3)
    genes = np.zeros((2, 10, 5))
    draws = BlockDraws([np.random.default_rng(0)], 10)
    with pytest.raises(ShapeError, match="need draws for 2 runs; got 1"):
        next_generation(genes, [0, 0], [[1], [1]], 0, draws=draws)
    with pytest.raises(ShapeError, match=r"\(n_runs, n_faces, n_genes\)"):
        next_generation(genes[0], [0], [[1]], 0, draws=draws)
    two = BlockDraws([np.random.default_rng(0), np.random.default_rng(1)], 10)
    with pytest.raises(SelectionError, match="must be in"):
        next_generation(genes, [0, 10], [[1], [1]], 0, draws=two)
    with pytest.raises(SelectionError, match="ranking"):
        classical_next_generation(genes, [[0, 12], [1, 2]], draws=two)
