"""Dynamic genes: the closed-form curve and the operators' sampling, against plain loops.

The references here are written from docs/ga.md ("Dynamic faces"), scalar by scalar, reading
stream 2's block of doubles front to back — not from the vectorised code.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from emogen.errors import ConfigError, ShapeError
from emogen.ga.algorithm import next_generation
from emogen.ga.draws import BlockDraws
from emogen.ga.genome import STATIC, DynamicGenome, frame_times, genome_of

unit = st.floats(0.0, 1.0, allow_nan=False)
timings = st.lists(unit, min_size=5, max_size=5)
GENOME = DynamicGenome()


# ---- the curve -----------------------------------------------------------------------------
def curve_loop(timing: list[float], t: float, d: float = 1.25, s: float = 0.08) -> float:
    """The documented curve, one time at a time."""
    o, acc, p, dec, f = timing
    t_on = o * (d - 2 * s)
    t_peak = t_on + s + p * (d - 2 * s - t_on)
    t_off = t_peak + s + f * (d - s - t_peak)
    if t <= t_on or t >= t_off:
        return 0.0
    if t <= t_peak:
        x, m = (t - t_on) / (t_peak - t_on), 3 * acc
    else:
        x, m = (t_off - t) / (t_off - t_peak), 3 * dec
    return 3 * x * x - 2 * x**3 + m * (x**3 - 2 * x * x + x)


@settings(max_examples=200, deadline=None)
@given(timing=timings, amp=unit, t=st.floats(-0.5, 2.0))
def test_curve_equals_the_plain_formula(timing, amp, t) -> None:
    gene = np.array([[amp, *timing]])
    got = GENOME.weights_at(gene, np.array([t]))[0, 0]
    assert math.isclose(got, amp * curve_loop(timing, t), rel_tol=1e-12, abs_tol=1e-12)


@settings(max_examples=150, deadline=None)
@given(timing=timings)
def test_any_parameters_give_an_ordered_curve_that_rises_to_one_and_returns_to_rest(timing) -> None:
    gene = np.array([[1.0, *timing]])
    t_on, t_peak, t_off = (float(v[0]) for v in GENOME.times(gene))
    assert t_on >= 0 and t_on + 0.08 <= t_peak + 1e-12 and t_peak + 0.08 <= t_off + 1e-12
    assert t_off <= 1.25 + 1e-12
    t = np.linspace(0, 1.25, 2501)
    w = GENOME.weights_at(gene, t)[:, 0]
    assert w.min() >= 0 and w.max() <= 1 + 1e-12
    assert math.isclose(GENOME.weights_at(gene, np.array([t_peak]))[0, 0], 1.0)
    assert w[t <= t_on].max(initial=0) == 0 and w[t >= t_off].max(initial=0) == 0
    rising = w[(t >= t_on) & (t <= t_peak)]
    falling = w[(t >= t_peak) & (t <= t_off)]
    assert np.all(np.diff(rising) >= -1e-12) and np.all(np.diff(falling) <= 1e-12)
    # continuous: no step between samples 0.5 ms apart larger than the steepest slope allows
    assert np.abs(np.diff(w)).max() <= 3 / 0.08 * (t[1] - t[0]) + 1e-9


def test_acceleration_and_deceleration_shape_the_start_and_the_end() -> None:
    slow, abrupt = [0.2, 0.0, 0.5, 0.0, 0.5], [0.2, 1.0, 0.5, 1.0, 0.5]
    t_on, t_peak, t_off = (float(v) for v in GENOME.times(np.array([1.0, *slow])))
    early, late = t_on + 0.1 * (t_peak - t_on), t_off - 0.1 * (t_off - t_peak)
    for t in (early, late):
        a = curve_loop(abrupt, t)
        b = curve_loop(slow, t)
        assert a > 2 * b > 0  # an abrupt start (end) is far further from rest near the onset


def test_frames_span_the_clip() -> None:
    t = frame_times(GENOME, 30)
    assert t[0] == 0 and t[-1] == 1.25 and np.allclose(np.diff(t), 1.25 / 38)
    with pytest.raises(ConfigError, match="fps must be in"):
        frame_times(GENOME, 0)


@pytest.mark.parametrize(
    ("spec", "match"),
    [
        ({"kind": "dynamic", "clip_s": 0.1}, "clip_s must be in"),
        ({"kind": "dynamic", "hold_s": -1}, "hold_s must be in"),
        ({"kind": "dynamic", "min_segment_s": 0.5}, "min_segment_s must be in"),
        ({"kind": "dynamic", "clip_s": "long"}, "clip_s must be a number"),
        ({"kind": "dynamic", "fps": 3}, r"unknown key\(s\) \['fps'\]"),
        ({"kind": "static"}, "genome must be null"),
    ],
)
def test_bad_genome_specs_are_named(spec, match) -> None:
    with pytest.raises(ConfigError, match=match):
        genome_of(spec)


def test_a_genome_round_trips_through_its_record() -> None:
    genome = DynamicGenome(clip_s=2.0, hold_s=0.25)
    assert genome_of(genome.to_dict()) == genome and genome_of(None) is STATIC


# ---- the operators, against plain loops reading the block ------------------------------------
class Reader:
    """Stream 2 read by hand: uniforms as they come, integers ⌊u·k⌋, pairs as documented."""

    def __init__(self, block: np.ndarray) -> None:
        self.values, self.at = [float(v) for v in block], 0

    def u(self) -> float:
        self.at += 1
        return self.values[self.at - 1]

    def int(self, k: int) -> int:
        return min(math.floor(self.u() * k), k - 1)

    def pair(self, s: int) -> tuple[int, int]:
        a = min(math.floor(self.u() * s), s - 1)
        b = min(math.floor(self.u() * (s - 1)), s - 2)
        return a, b + (b >= a)


def mutate_loop(gene: list[list[float]], m: int, r: Reader) -> list[list[float]]:
    k = len(gene)
    index = [r.int(k) for _ in range(m)]
    amp = [r.u() for _ in range(m)]
    coin = [r.u() for _ in range(m)]
    timing = [[r.u() for _ in range(5)] for _ in range(m)]
    out = [list(g) for g in gene]
    for j in range(m):
        if coin[j] < 0.5:
            out[index[j]][0] = amp[j]
        else:
            out[index[j]][1:] = timing[j]
    return out


def random_loop(n: int, k: int, x: int, r: Reader) -> list[list[list[float]]]:
    index = [[r.int(k) for _ in range(x)] for _ in range(n)]
    values = [[r.u() for _ in range(x)] for _ in range(n)]
    faces = [[[0.0] + [r.u() for _ in range(5)] for _ in range(k)] for _ in range(n)]
    for i in range(n):
        for j in range(x):
            faces[i][index[i][j]][0] = values[i][j]
    return faces


def average_loop(members: list[list[list[float]]]) -> list[list[float]]:
    out = []
    for gene in zip(*members, strict=True):
        amps = [g[0] for g in gene]
        w = amps if sum(amps) > 0 else [1.0] * len(gene)
        timing = [
            sum(wi * g[1 + p] for wi, g in zip(w, gene, strict=True)) / sum(w) for p in range(5)
        ]
        out.append([sum(amps) / len(amps), *timing])
    return out


def next_generation_loop(genes, elite, others, g, block, n_random=4, m=2, x=6):  # type: ignore[no-untyped-def]
    """Algorithm 1 for one run, as docs/ga.md's table says, slot by slot."""
    r = Reader(block)
    n, k = len(genes), len(genes[0])
    selected = [elite, *others]
    s = len(selected)
    out = []
    for slot in range(1, n - n_random + 1):
        if slot == 1:
            out.append([list(v) for v in genes[elite]])
        elif slot == 2 and s > 2:
            out.append(average_loop([genes[i] for i in selected]))
        elif slot == 3 and g not in (1, 2):
            if s >= 2:
                other = others[r.int(s - 1)]
                out.append(average_loop([genes[elite], genes[other]]))
            else:
                out.append([list(v) for v in genes[2]])
        else:
            if s >= 2:
                a, b = (selected[i] for i in r.pair(s))
                mask = [r.u() < 0.5 for _ in range(k)]
                child = [list(genes[b][i] if mask[i] else genes[a][i]) for i in range(k)]
            else:
                child = [list(v) for v in genes[elite]]
            out.append(mutate_loop(child, m, r))
    return out + random_loop(n_random, k, x, r)


def dynamic_population(n: int, k: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    genes = rng.random((n, k, 6))
    genes[..., 0][rng.random((n, k)) < 0.6] = 0.0
    return genes


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    g=st.integers(0, 6),
    n_sel=st.integers(1, 10),
    k=st.integers(1, 12),
    m=st.integers(0, 4),
)
def test_algorithm_1_on_dynamic_genes_equals_a_plain_loop(seed, g, n_sel, k, m) -> None:
    genes = dynamic_population(10, k, seed)
    order = np.random.default_rng(seed + 1).permutation(10)
    elite, others = int(order[0]), [int(i) for i in order[1:n_sel]]
    size = 10 * (3 + k + 2 * m + 12 + GENOME.extra_draws(k, m))
    block = np.random.default_rng(seed + 2).random(size)
    draws = BlockDraws([np.random.default_rng(seed + 2)], size)
    off = next_generation(
        genes[None],
        np.array([elite]),
        np.array(others, dtype=int)[None],
        g,
        draws=draws,
        mutation_genes=m,
        genome=GENOME,
    )
    expected = np.array(next_generation_loop(genes.tolist(), elite, others, g, block, m=m))
    assert off.genes.shape == (1, 10, k, 6)
    np.testing.assert_allclose(off.genes[0], expected, rtol=1e-12, atol=1e-15)


def test_crossover_exchanges_whole_genes() -> None:
    a, b = dynamic_population(1, 30, 1)[0], dynamic_population(1, 30, 2)[0]
    off = next_generation(
        np.stack([a, b, a, b])[None],
        np.array([0]),
        np.array([[1]]),
        1,
        draws=BlockDraws([np.random.default_rng(3)], 5000),
        random_faces_count=1,
        mutation_genes=0,
        genome=GENOME,
    )
    child = off.genes[0, 1]  # slot 2 with S = 2: crossover, no mutation
    from_a = (child == a).all(axis=1)
    from_b = (child == b).all(axis=1)
    assert np.all(from_a | from_b) and from_a.any() and from_b.any()


def test_mutation_changes_the_amplitude_or_the_timing_of_a_gene_never_both() -> None:
    genes = dynamic_population(2000, 30, 4)[None]
    out = GENOME.mutate(genes, 1, BlockDraws([np.random.default_rng(5)], 2000 * 8))
    changed = out != genes
    amp_only = changed[..., 0] & ~changed[..., 1:].any(-1)
    timing_only = ~changed[..., 0] & changed[..., 1:].all(-1)
    both = changed[..., 0] & changed[..., 1:].any(-1)
    assert not both.any()
    n_amp, n_timing = int(amp_only.sum()), int(timing_only.sum())
    assert n_amp + n_timing == 2000  # one gene changed per face (values are continuous)
    assert 0.45 < n_amp / 2000 < 0.55


def test_random_faces_carry_every_genes_timing_and_at_most_x_amplitudes() -> None:
    faces = GENOME.random(50, 30, 6, BlockDraws([np.random.default_rng(6)], 50 * 200))[0]
    assert faces.shape == (50, 30, 6)
    assert ((faces[..., 0] > 0).sum(axis=1) <= 6).all()
    assert (faces[..., 1:] > 0).all() and (faces[..., 1:] < 1).all()


def test_dynamic_genes_of_the_wrong_shape_are_refused() -> None:
    with pytest.raises(ShapeError, match=r"n_genes, 6\); got \(1, 10, 30\)"):
        next_generation(
            np.zeros((1, 10, 30)),
            np.array([0]),
            np.zeros((1, 0), dtype=int),
            0,
            draws=BlockDraws([np.random.default_rng(0)], 10),
            genome=GENOME,
        )
