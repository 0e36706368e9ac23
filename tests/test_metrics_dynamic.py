"""Similarity of dynamic faces (emogen.metrics.dynamic) against plain loops over time samples."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.spatial.distance import cosine

from emogen.errors import ShapeError
from emogen.ga.genome import DynamicGenome
from emogen.metrics import cosine_distance
from emogen.metrics.dynamic import timing_distance, trajectory_cd
from emogen.simulate.dynamic import latencies, sample_times, trajectory

GENOME = DynamicGenome()
D, DELTA = GENOME.clip_s, GENOME.min_segment_s
#: 4 genes over 6 shapes: gene 0 → shapes 0, 1 (a pair); 1 → 2; 2 → 3, 4; 3 → 5.
EXPANSION = np.array(
    [
        [1, 1, 0, 0, 0, 0],
        [0, 0, 1, 0, 0, 0],
        [0, 0, 0, 1, 1, 0],
        [0, 0, 0, 0, 0, 1],
    ],
    dtype=float,
)
TIMES = sample_times(GENOME, 26)


def peak_cd(a: np.ndarray, b: np.ndarray, expansion: np.ndarray) -> np.ndarray:
    """The peak shape's distance: the static CD of the peak profiles."""
    return cosine_distance(a[..., 0] @ expansion, b[..., 0] @ expansion)


def timing(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return timing_distance(latencies(GENOME, a), a[..., 0], latencies(GENOME, b), b[..., 0])


def plain_weight(gene: np.ndarray, t: float) -> float:
    """docs/ga.md's curve, written out for one gene and one time."""
    amp, o, a, p, d, f = (float(x) for x in gene)
    t_on = o * (D - 2 * DELTA)
    t_peak = t_on + DELTA + p * (D - 2 * DELTA - t_on)
    t_off = t_peak + DELTA + f * (D - DELTA - t_peak)

    def h(x: float, m: float) -> float:
        return 3 * x * x - 2 * x**3 + m * (x**3 - 2 * x * x + x)

    if t <= t_on or t >= t_off:
        return 0.0
    if t <= t_peak:
        return amp * h((t - t_on) / (t_peak - t_on), 3 * a)
    return amp * h((t_off - t) / (t_off - t_peak), 3 * d)


def plain_trajectory_cd(a: np.ndarray, b: np.ndarray) -> float:
    """CD over every (time, shape) sample, accumulated one sample at a time."""
    dot = na = nb = 0.0
    for t in TIMES:
        for s in range(EXPANSION.shape[1]):
            wa = sum(plain_weight(a[k], t) * EXPANSION[k, s] for k in range(len(a)))
            wb = sum(plain_weight(b[k], t) * EXPANSION[k, s] for k in range(len(b)))
            dot, na, nb = dot + wa * wb, na + wa * wa, nb + wb * wb
    if na == 0 or nb == 0:
        return 0.0 if na == nb else 1.0
    return 1 - dot / math.sqrt(na * nb)


def plain_timing(a: np.ndarray, b: np.ndarray) -> float:
    num = den = 0.0
    for ga, gb in zip(a, b, strict=True):
        w = ga[0] * gb[0]
        la, lb = latencies_of(ga), latencies_of(gb)
        num += w * sum((x - y) ** 2 for x, y in zip(la, lb, strict=True))
        den += w
    return math.sqrt(num / (3 * den)) if den > 0 else math.nan


def latencies_of(gene: np.ndarray) -> tuple[float, float, float]:
    o, p, f = gene[1], gene[3], gene[5]
    t_on = o * (D - 2 * DELTA)
    t_peak = t_on + DELTA + p * (D - 2 * DELTA - t_on)
    return t_on, t_peak, t_peak + DELTA + f * (D - DELTA - t_peak)


def gene_at(amp: float, t_on: float, t_peak: float, t_off: float, acc: float, dec: float):
    """A gene with the given latencies (s): the stick-breaking of docs/ga.md inverted."""
    o = t_on / (D - 2 * DELTA)
    p = (t_peak - t_on - DELTA) / (D - 2 * DELTA - t_on)
    f = (t_off - t_peak - DELTA) / (D - DELTA - t_peak)
    return np.array([amp, o, acc, p, dec, f])


#: Values 0 or ≥ 1e-3 (no subnormals: eq. 12 has no meaning for vectors that round to 0).
faces = arrays(np.float64, (4, 6), elements=st.just(0.0) | st.floats(1e-3, 1))


@settings(max_examples=40, deadline=None)
@given(a=faces, b=faces)
def test_the_three_distances_equal_plain_loops_and_are_symmetric(a, b) -> None:
    ta = trajectory(GENOME, a, EXPANSION, TIMES)
    tb = trajectory(GENOME, b, EXPANSION, TIMES)
    total = float(trajectory_cd(ta, tb))
    assert total == pytest.approx(plain_trajectory_cd(a, b), abs=1e-9)
    assert total == pytest.approx(float(trajectory_cd(tb, ta)), abs=1e-12)
    peak = float(peak_cd(a, b, EXPANSION))
    if a[:, 0].any() and b[:, 0].any():
        assert peak == pytest.approx(cosine(a[:, 0] @ EXPANSION, b[:, 0] @ EXPANSION), abs=1e-9)
    assert peak == pytest.approx(float(peak_cd(b, a, EXPANSION)), abs=1e-12)
    apart = float(timing(a, b))
    expected = plain_timing(a, b)
    if math.isnan(expected):
        assert math.isnan(apart)
    else:
        assert apart == pytest.approx(expected, abs=1e-9)
        assert apart == pytest.approx(float(timing(b, a)), abs=1e-12)


@settings(max_examples=40, deadline=None)
@given(a=faces)
def test_a_face_is_at_distance_zero_from_itself(a) -> None:
    ta = trajectory(GENOME, a, EXPANSION, TIMES)
    assert float(trajectory_cd(ta, ta)) == pytest.approx(0, abs=1e-12)
    assert float(peak_cd(a, a, EXPANSION)) == pytest.approx(0, abs=1e-12)
    if (a[:, 0] > 0).any():
        assert float(timing(a, a)) == 0


@settings(max_examples=40, deadline=None)
@given(
    amps=arrays(np.float64, (2, 4), elements=st.floats(0.05, 1)),
    course=arrays(np.float64, (5,), elements=st.floats(0, 1)),
)
def test_faces_with_one_shared_time_course_have_the_papers_static_cd(amps, course) -> None:
    """Every gene of both faces moves with the same curve: the total is the static CD (eq. 12)
    of their peak weights, and the timing distance is 0."""
    a = np.column_stack([amps[0], np.tile(course, (4, 1))])
    b = np.column_stack([amps[1], np.tile(course, (4, 1))])
    ta = trajectory(GENOME, a, EXPANSION, TIMES)
    tb = trajectory(GENOME, b, EXPANSION, TIMES)
    static = cosine(amps[0] @ EXPANSION, amps[1] @ EXPANSION)
    assert float(trajectory_cd(ta, tb)) == pytest.approx(static, abs=1e-9)
    assert float(peak_cd(a, b, EXPANSION)) == pytest.approx(static, abs=1e-9)
    assert float(timing(a, b)) == pytest.approx(0, abs=1e-12)


def test_a_clip_moved_later_is_further_the_more_it_moves() -> None:
    """Every gene's onset, peak and offset moved by Δ (the curve's shape kept): the total
    grows with Δ from 0 (to 1 once the clips no longer overlap), the timing distance is Δ, the
    peak shape stays 0."""
    base = [(0.8, 0.05, 0.25, 0.45), (0.5, 0.10, 0.30, 0.55), (0.6, 0.0, 0.20, 0.40)]

    def face(shift: float) -> np.ndarray:
        genes = [
            gene_at(a, on + shift, pk + shift, off + shift, 0.3, 0.6) for a, on, pk, off in base
        ]
        return np.array([*genes, np.zeros(6)])

    ref = face(0.0)
    totals, timings = [], []
    for shift in (0.0, 0.02, 0.05, 0.1, 0.2, 0.4, 0.6):
        moved = face(shift)
        t_ref = trajectory(GENOME, ref, EXPANSION, TIMES)
        t_moved = trajectory(GENOME, moved, EXPANSION, TIMES)
        totals.append(float(trajectory_cd(t_ref, t_moved)))
        timings.append(float(timing(ref, moved)))
        assert float(peak_cd(ref, moved, EXPANSION)) == pytest.approx(0, abs=1e-12)
        assert timings[-1] == pytest.approx(shift, abs=1e-12)
        assert totals[-1] == pytest.approx(plain_trajectory_cd(ref, moved), abs=1e-9)
    assert totals[0] == pytest.approx(0, abs=1e-12)
    assert all(x > 0 for x in totals[1:])
    # it grows until the clips no longer overlap (the latest offset, 0.55 s, before the shift
    # of 0.4 s): then they are orthogonal, CD 1, and only the timing distance keeps growing
    assert all(b > a for a, b in itertools.pairwise(totals[:5])), totals
    assert totals[4] < 1 and totals[5] == totals[6] == pytest.approx(1, abs=1e-12)


def test_timing_cannot_be_compared_without_a_gene_both_faces_show() -> None:
    a = np.zeros((4, 6))
    b = np.zeros((4, 6))
    a[0] = [0.7, 0.1, 0.5, 0.5, 0.5, 0.5]
    b[1] = [0.7, 0.1, 0.5, 0.5, 0.5, 0.5]
    assert math.isnan(float(timing(a, b)))
    # batched: one row comparable, one not
    out = timing(np.stack([a, a]), np.stack([a, b]))
    assert out[0] == 0 and math.isnan(out[1])


def test_batches_compare_row_by_row_and_broadcast_one_target() -> None:
    rng = np.random.default_rng(3)
    many = rng.random((5, 4, 6))
    target = rng.random((4, 6))
    t_many = trajectory(GENOME, many, EXPANSION, TIMES)
    t_target = trajectory(GENOME, target, EXPANSION, TIMES)
    assert t_many.shape == (5, 26, 6)
    got = trajectory_cd(t_many, t_target)
    for i in range(5):
        assert got[i] == pytest.approx(plain_trajectory_cd(many[i], target), abs=1e-9)
    np.testing.assert_allclose(
        peak_cd(many, target, EXPANSION),
        cosine_distance(many[..., 0] @ EXPANSION, target[:, 0] @ EXPANSION),
    )


def test_bad_shapes_are_named() -> None:
    with pytest.raises(ShapeError, match=r"latencies must be \(…, n_genes, 3\).*\(4, 2\)"):
        timing_distance(np.zeros((4, 2)), np.ones(4), np.zeros((4, 3)), np.ones(4))
    with pytest.raises(ShapeError, match=r"amplitudes \(…, n_genes\) must match"):
        timing_distance(np.zeros((4, 3)), np.ones(5), np.zeros((4, 3)), np.ones(4))
    with pytest.raises(ShapeError, match="same times and shapes"):
        trajectory_cd(np.zeros((26, 6)), np.zeros((21, 6)))
