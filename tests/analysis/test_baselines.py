"""Chance baselines: the one-to-one matched accuracy against a brute-force search over every
matching, and the permutation distribution against what chance must give."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from sklearn.metrics import adjusted_rand_score

from emogen.analysis.replication.baselines import (
    matched_correct,
    permutation_chance,
)


def _brute_force(labels: np.ndarray, predicted: np.ndarray) -> float:
    """The best share over every one-to-one map of labels to clusters (a plain loop)."""
    k, c = labels.max() + 1, predicted.max() + 1
    best = 0
    for clusters in itertools.permutations(range(int(max(k, c))), int(k)):
        best = max(best, sum(int(predicted[i] == clusters[labels[i]]) for i in range(len(labels))))
    return best / len(labels)


@pytest.mark.parametrize("seed", range(5))
def test_matched_accuracy_is_the_best_one_to_one_matching(seed: int) -> None:
    rng = np.random.default_rng(seed)
    labels = rng.integers(0, 3, 60)
    predicted = np.where(rng.random(60) < 0.6, labels, rng.integers(0, 4, 60))
    assert matched_correct(labels, predicted).mean() == pytest.approx(
        _brute_force(labels, predicted)
    )


def test_a_lump_leaves_one_target_wrong() -> None:
    labels = np.repeat([0, 1, 2], 10)
    predicted = np.repeat([0, 0, 1], 10)  # targets 0 and 1 in one cluster
    assert matched_correct(labels, predicted).mean() == pytest.approx(20 / 30)


def test_permutation_chance_is_near_a_third_for_three_clean_clusters() -> None:
    labels = np.repeat([0, 1, 2], 300)
    chance = permutation_chance(labels, labels.copy(), np.random.default_rng(0), 200)
    # perfect clusters score 100%; with labels permuted the matched share is near 1/3 and
    # the ARI near 0 (sklearn's ARI of independent labels is 0 in expectation)
    assert 0.33 < chance.accuracy_mean < 0.37 and chance.accuracy_95 < 0.40
    assert abs(chance.ari_mean) < 0.005 and chance.ari_95 < 0.01
    shuffled = np.random.default_rng(1).permutation(labels)
    assert abs(adjusted_rand_score(shuffled, labels)) < chance.ari_95 + 0.01


def test_bad_inputs_are_named() -> None:
    with pytest.raises(ValueError, match="equal 1-d arrays"):
        matched_correct(np.zeros(3, dtype=int), np.zeros(4, dtype=int))
    with pytest.raises(ValueError, match="permutations must be ≥ 1; got 0"):
        permutation_chance(
            np.zeros(3, dtype=int), np.zeros(3, dtype=int), np.random.default_rng(), 0
        )


def test_chance_faces_are_initial_faces_without_a_target(ict_model) -> None:
    from emogen.analysis.repeatability import repeatability_bins
    from emogen.analysis.replication.baselines import chance_faces

    rig = ict_model.rig
    faces = chance_faces(rig, 60, np.random.default_rng(4))
    assert faces.shape == (60, len(rig.shape_names))
    np.testing.assert_array_equal(faces, chance_faces(rig, 60, np.random.default_rng(4)))
    genes = rig.contract(faces, True)
    active = (genes > 0).sum(axis=1)
    assert active.min() >= 1 and active.max() <= 8  # 3–8 drawn genes (emotion faces: capped)
    # unrelated faces rarely pair up in the first repeatability bin
    assert repeatability_bins(faces)[0] < 0.3
    with pytest.raises(ValueError, match="count must be ≥ 1; got 0"):
        chance_faces(rig, 0, np.random.default_rng(0))
