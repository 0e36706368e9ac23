"""PCA + GMM separability with cluster-to-group correspondence (Table I) on known answers."""

from __future__ import annotations

import numpy as np
import pytest

from emogen.analysis.separability import gmm_separability
from emogen.errors import ConfigError


def blobs(
    centres: list[np.ndarray], n: int, sd: float, seed: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    x = np.concatenate([c + rng.normal(0, sd, (n, len(c))) for c in centres])
    return x, np.repeat(np.arange(len(centres)), n)


def test_two_well_separated_clusters_are_found() -> None:
    a, b = np.zeros(10), np.full(10, 1.0)
    x, y = blobs([a, b], 150, 0.05)
    sep = gmm_separability(x, y, ["A", "B"], targets=np.stack([a, b]))
    assert sep.accuracy == 1.0 and sep.one_to_one and sep.ari == pytest.approx(1.0)
    assert sorted(sep.cluster_names) == ["A", "B"]
    assert sep.cluster_of_target == sep.cluster_of_group
    conf = sep.confusion
    assert conf.loc["A samples", "A"] == 150 and conf.loc["A samples", "B"] == 0
    assert conf.loc["B samples", "B"] == 150
    assert sep.coords.shape == (300, 2) and sep.target_coords is not None


def test_identical_groups_are_lumped_and_the_third_found() -> None:
    """Groups 1 and 3 from one distribution, group 2 far away: like ED in Table I."""
    c1, c2 = np.zeros(6), np.full(6, 2.0)
    x, y = blobs([c1, c2, c1], 200, 0.1, seed=1)
    sep = gmm_separability(x, y, ["target 1", "target 2", "target 3"])
    assert sep.per_group_accuracy["target 2"] == 1.0
    assert sep.accuracy < 0.75  # 1 and 3 cannot both be right
    if not sep.one_to_one:
        assert "target 1 and target 3" in sep.cluster_names
        assert any(n.startswith("unnamed") for n in sep.cluster_names)


def test_more_pca_components_by_variance_share() -> None:
    x, y = blobs([np.zeros(8), np.full(8, 1.0), np.r_[np.full(4, 1.0), np.zeros(4)]], 80, 0.05, 2)
    sep = gmm_separability(x, y, ["a", "b", "c"], n_pca=0.95)
    assert sep.n_pca >= 2 and sep.accuracy == 1.0


def test_separability_checks_its_input() -> None:
    x, y = blobs([np.zeros(3), np.ones(3)], 3, 0.1)
    with pytest.raises(ConfigError, match="every group"):
        gmm_separability(x, y, ["a", "b", "c"])
    with pytest.raises(ConfigError, match="at least 2 clusters"):
        gmm_separability(x, np.zeros(len(x), dtype=int), ["a"])
    with pytest.raises(ConfigError, match="samples"):
        gmm_separability(x[[0, 3]], np.array([0, 1]), ["a", "b"])
