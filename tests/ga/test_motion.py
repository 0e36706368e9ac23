"""Dynamic faces over time: keyframe correction, interpolation, and interpenetration at dense
frames between keyframes (the independent winding-number test)."""

from __future__ import annotations

import numpy as np
import pytest

from emogen.correct import correct_faces
from emogen.correct.lips import mouth_geometry
from emogen.correct.measure import Interpenetration
from emogen.ga.genome import DynamicGenome, keyframe_times
from emogen.ga.motion import _distinct, correct_keyframes, frames, interpolate

GENOME = DynamicGenome()


def test_interpolation_equals_numpys_interp_column_by_column() -> None:
    rng = np.random.default_rng(0)
    keyed = rng.random((3, GENOME.keyframes, 4))
    t = np.r_[-0.1, rng.uniform(0, 1.25, 50), keyframe_times(GENOME), 1.4]
    got = interpolate(GENOME, keyed, t)
    for i in range(3):
        for c in range(4):
            want = np.interp(t, keyframe_times(GENOME), keyed[i, :, c])
            np.testing.assert_allclose(got[i, :, c], want, rtol=1e-12, atol=1e-14)


def test_frames_are_the_exact_curve_then_the_interpolated_correctives(ict_model) -> None:
    rng = np.random.default_rng(1)
    genes = rng.random((2, len(ict_model.rig.gene_names(True)), 6))
    expand = lambda g: ict_model.rig.expand(g, True)  # noqa: E731
    t = np.array([0.0, 0.3, 0.71, 1.25])
    keyed = rng.random((2, GENOME.keyframes, 5))
    shown = frames(GENOME, genes, keyed, t, expand)
    s = ict_model.n_shapes
    for i in range(2):
        for j, tj in enumerate(t):
            core = expand(GENOME.weights_at(genes[i], np.array([tj]))[0][None])[0]
            np.testing.assert_array_equal(shown[i, j, :s], core)
    np.testing.assert_array_equal(shown[..., s:], interpolate(GENOME, keyed, t))
    assert frames(GENOME, genes, None, t, expand).shape == (2, 4, s)


def test_distinct_keyframes_are_numpys_unique_rows_in_order_of_first_appearance() -> None:
    rng = np.random.default_rng(4)
    rows = np.round(rng.random((400, 9)), 1)
    rows[rng.random(400) < 0.4] = 0.0  # many at rest, as a clip's ends are
    distinct, where = _distinct(rows)
    np.testing.assert_array_equal(distinct[where], rows)
    np.testing.assert_array_equal(np.unique(distinct, axis=0), np.unique(rows, axis=0))
    assert len(distinct) == len(np.unique(rows, axis=0))
    firsts = [int(np.flatnonzero((rows == d).all(axis=1))[0]) for d in distinct]
    assert firsts == sorted(firsts)


def test_keyframes_are_corrected_as_every_keyframe_alone(ict_model) -> None:
    from benchmarks.bench_motion import dynamic_faces

    genes = dynamic_faces(ict_model, 12, seed=3)
    expand = lambda g: ict_model.rig.expand(g, True)  # noqa: E731
    calls: list[int] = []

    def correct(w):  # type: ignore[no-untyped-def]
        calls.append(len(w))
        r = correct_faces(ict_model, w)
        return r.corrective_names, r.correctives

    names, keyed = correct_keyframes(GENOME, genes, expand, correct)
    assert keyed.shape == (12, GENOME.keyframes, len(names))
    assert calls[0] < 12 * GENOME.keyframes  # frames at rest are corrected once
    core = GENOME.weights_at(genes, keyframe_times(GENOME))
    for i in (0, 5, 11):
        alone = correct_faces(ict_model, expand(core[i])).correctives
        np.testing.assert_array_equal(keyed[i], alone)


def test_interpenetration_between_keyframes_stays_within_the_measured_bound(ict_model) -> None:
    """Dense frames (50/s) of 30 dynamic GA faces: with correctives interpolated between the 21
    keyframes, few frames interpenetrate, and shallowly (benchmarks/bench_motion.py measured
    1.0 % of frames, deepest 0.8 mm, at 21 keyframes; 18.7 % uncorrected)."""
    from benchmarks.bench_motion import dynamic_faces, measure

    neutral = ict_model.base_neutral.astype(np.float64)
    mouth = mouth_geometry(neutral, ict_model.polygons, ict_model.regions)
    test = Interpenetration.build(neutral, ict_model.regions, mouth)
    genes = dynamic_faces(ict_model, 30, seed=5)
    r = measure(ict_model, genes, GENOME.keyframes, 50.0, test)
    assert r["uncorrected"] > 0.08  # the clips collide: the test has something to find
    assert r["interpolated"] <= 0.025, r
    assert r["deepest_mm"] <= 1.5, r
    assert r["interpolated"] <= r["uncorrected"] / 6, r


@pytest.mark.parametrize("keyframes", [1, 201, 2.5, True])
def test_bad_keyframe_counts_are_named(keyframes) -> None:
    from emogen.errors import ConfigError

    with pytest.raises(ConfigError, match="keyframes must be an integer in \\[2, 200\\]"):
        DynamicGenome(keyframes=keyframes)
