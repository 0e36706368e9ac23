"""Repeatability bins (Table III) and target bias, against brute-force references."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.distance import pdist

from emogen.analysis.repeatability import (
    best_initial_error,
    bins_frame,
    initial_bias,
    pairwise_cd_counts,
    repeatability_bins,
)
from emogen.errors import ShapeError


def test_identical_faces_all_fall_in_the_first_bin() -> None:
    face = np.random.default_rng(0).random(57)
    faces = np.tile(face, (40, 1))
    np.testing.assert_array_equal(repeatability_bins(faces), [1.0, 0.0, 0.0, 0.0])
    # scaled copies too: CD ignores intensity
    scaled = face[None] * np.linspace(0.2, 1.0, 30)[:, None]
    np.testing.assert_allclose(repeatability_bins(scaled), [1.0, 0.0, 0.0, 0.0])


def test_orthogonal_faces_fall_in_the_last_bin() -> None:
    np.testing.assert_array_equal(repeatability_bins(np.eye(6)), [0.0, 0.0, 0.0, 1.0])


def test_counts_match_scipy_pdist_in_blocks() -> None:
    rng = np.random.default_rng(1)
    faces = rng.random((203, 12)) * (rng.random((203, 12)) < 0.4)
    faces[faces.sum(1) == 0, 0] = 0.5  # no zero vectors for scipy
    cd = pdist(faces, "cosine")
    ref = np.histogram(np.clip(cd, 0, 1), bins=[0, 0.25, 0.5, 0.75, 1.0 + 1e-12])[0]
    np.testing.assert_array_equal(pairwise_cd_counts(faces, block=17), ref)
    assert pairwise_cd_counts(faces).sum() == 203 * 202 // 2


def test_zero_faces_follow_the_cd_convention() -> None:
    faces = np.array([[0.0, 0.0], [0.0, 0.0], [1.0, 0.0]])
    # two zero faces: CD 0; zero vs non-zero: CD 1
    np.testing.assert_array_equal(pairwise_cd_counts(faces), [1, 0, 0, 2])


def test_fewer_than_two_faces_give_nan() -> None:
    assert np.isnan(repeatability_bins(np.ones((1, 3)))).all()
    with pytest.raises(ShapeError):
        repeatability_bins(np.ones(3))


def test_best_initial_error_is_the_closest_option() -> None:
    rng = np.random.default_rng(2)
    init = rng.random((5, 10, 8))
    target = rng.random(8)
    ref = [
        min(1 - f @ target / np.linalg.norm(f) / np.linalg.norm(target) for f in pop)
        for pop in init
    ]
    np.testing.assert_allclose(best_initial_error(init, target), ref)
    # a population holding the target itself has no bias left
    init[0, 3] = target * 0.3
    assert best_initial_error(init, target)[0] == pytest.approx(0.0, abs=1e-12)
    mean, sd = initial_bias(np.array([1.0, 1.0]))
    assert (mean, sd) == (1.0, 0.0)


def test_bins_frame_in_percent() -> None:
    df = bins_frame({"a": np.array([0.25, 0.25, 0.5, 0.0])})
    assert df.loc["a"].tolist() == [25.0, 25.0, 50.0, 0.0]
