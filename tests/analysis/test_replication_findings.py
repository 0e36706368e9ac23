"""The findings added for issue #30 item 3 (Fig. 11's low-variance target, std_ED clustering,
interpenetration and plausibility of shown faces, the inter-sample statistic): each rule made to
return each of its verdicts on constructed cases, and the statistics against plain references."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.distance import pdist

from emogen.analysis.replication.baselines import Chance
from emogen.analysis.replication.conditions import Condition
from emogen.analysis.replication.interpenetration import (
    implausible_finding,
    interpenetration_finding,
)
from emogen.analysis.replication.intersample import (
    ALPHA,
    KINDS,
    GroupTest,
    intersample_finding,
    pairwise_stats,
)
from emogen.analysis.replication.low_variance import (
    LowVarianceTarget,
    low_variance_finding,
    low_variance_target,
)
from emogen.analysis.replication.std_clustering import Clustering, cluster, clustering_finding

RNG = np.random.default_rng(30)


def condition(final_errors: np.ndarray) -> Condition:
    e = np.c_[np.ones((len(final_errors), 10)), final_errors]
    return Condition("c", e, np.zeros((len(e), 3)), e[:, 0], np.ones(3), np.zeros(len(e)))


TARGET = LowVarianceTarget({"jawForward": 1.0}, np.ones(3), 20, 0.98, 21, 0.01, 0.03)
BASE = RNG.normal(0.3, 0.05, 300)
JITTER = RNG.normal(0, 0.005, 300)


@pytest.mark.parametrize(
    ("ed", "std", "verdict"),
    [
        (BASE * 2.0, BASE, "holds"),  # ED worse in mean and spread
        (0.95 * BASE + 0.12, BASE, "partly"),  # worse in mean only, not in spread
        (BASE, BASE + 0.1 + JITTER, "differs"),
        (BASE + RNG.normal(0, 0.05, 300), BASE, "partly"),  # mean: a precise zero; spread: ED's
        (BASE[:12] + RNG.normal(0, 0.1, 12), BASE[:12], "inconclusive"),
    ],
)
def test_low_variance_rule_reaches_each_verdict(
    ed: np.ndarray, std: np.ndarray, verdict: str
) -> None:
    assert low_variance_finding(condition(ed), condition(std), TARGET).verdict == verdict


def test_low_variance_target_lies_along_the_genes_that_vary_least(ict_model) -> None:  # type: ignore[no-untyped-def]
    """Training faces whose genes vary by known SDs: the target is built on genes whose own
    training SD is below the median gene's, and the PCA keeps it."""
    from emogen.metrics import PCASpace

    rig = ict_model.rig
    n_genes = len(rig.gene_names())
    sd = np.linspace(0.05, 0.4, n_genes)
    RNG.shuffle(sd)
    genes = np.clip(0.5 + RNG.normal(0, 1, (3000, n_genes)) * sd, 0, 1)
    space = PCASpace.fit(rig.expand(genes))
    t = low_variance_target(space, rig)
    quiet = {g.name for g, s in zip(rig.genes, sd, strict=True) if s < np.median(sd) and not g.eye}
    assert set(t.named) <= quiet and t.low_share > 0.9
    assert max(t.named.values()) == 1.0 and min(t.named.values()) >= 0.05


def clustering(reading: str, std: float, ed: float, cd: float, n: int = 300) -> Clustering:
    def ones(share: float) -> np.ndarray:
        return (np.arange(n) < share * n).astype(np.int64)

    chance = Chance(0.3, 0.35, 0.0, 0.01, 200)
    return Clustering(reading, {"pca_ed": ones(ed), "std_ed": ones(std), "cd": ones(cd)}, chance)


@pytest.mark.parametrize(
    ("first", "second", "verdict"),
    [
        ((0.3, 0.95, 0.97), (0.5, 0.9, 0.99), "holds"),  # below both, in both readings
        ((0.9, 0.95, 0.9), (0.9, 0.97, 0.9), "partly"),  # below ED(β) only
        ((0.99, 0.5, 0.6), (0.99, 0.4, 0.5), "differs"),
        ((0.3, 0.95, 0.97), (0.99, 0.5, 0.6), "inconclusive"),  # the readings disagree
    ],
)
def test_clustering_rule_reaches_each_verdict(
    first: tuple[float, float, float], second: tuple[float, float, float], verdict: str
) -> None:
    found = clustering_finding([clustering("a", *first), clustering("b", *second)])
    assert found.verdict == verdict


def test_std_ed_geometry_is_misled_by_a_noisy_low_variance_component() -> None:
    """Two groups apart along a high-variance axis, with noise along an axis the training set
    hardly varies on: std_ED's geometry magnifies the noise, ED's does not."""
    from emogen.metrics import PCASpace

    train = np.c_[RNG.normal(0, 1.0, 2000), RNG.normal(0, 0.15, 2000), np.zeros(2000)] + 0.5
    space = PCASpace.fit(train)
    assert space.n_components == 2  # both axes kept
    y = np.repeat([0, 1], 150)
    faces = np.c_[np.where(y, 1.5, 0.5), 0.5 + RNG.normal(0, 0.45, 300), np.full(300, 0.5)]
    c = cluster(space, faces, y, "constructed", seed=0)
    assert c.correct["pca_ed"].mean() > 0.95 and c.correct["std_ed"].mean() < 0.8


DEPTH = np.r_[np.full(200, 0.1), np.zeros(300)]


@pytest.mark.parametrize(
    ("before", "after", "verdict"),
    [
        (DEPTH, np.zeros(500), "holds"),
        # the penetrating faces are cleaned, but 400 faces come to touch the lip (0.02 cm)
        (
            np.r_[np.full(60, 0.03), np.zeros(440)],
            np.r_[np.zeros(60), np.full(440, 0.02)],
            "partly",
        ),
        (DEPTH, np.r_[np.full(180, 0.1), np.zeros(320)], "differs"),
        (np.r_[np.full(5, 0.1), np.zeros(20)], np.r_[0.1, np.zeros(24)], "inconclusive"),
    ],
)
def test_interpenetration_rule_reaches_each_verdict(
    before: np.ndarray, after: np.ndarray, verdict: str
) -> None:
    assert interpenetration_finding(before, after).verdict == verdict


def test_interpenetration_needs_faces_that_penetrate() -> None:
    with pytest.raises(ValueError, match="too few"):
        interpenetration_finding(np.r_[0.1, np.zeros(9)], np.zeros(10))


@pytest.mark.parametrize(
    ("before", "after", "verdict"),
    [
        ((np.arange(400) < 200), (np.arange(400) < 50), "holds"),
        ((np.arange(400) < 50), (np.arange(400) < 200), "differs"),
        ((np.arange(400) < 100), (np.arange(400) % 4 == 0), "differs"),  # a precise zero
        ((np.arange(20) < 5), (np.arange(20) % 4 == 1), "inconclusive"),
    ],
)
def test_implausible_rule_reaches_each_verdict(
    before: np.ndarray, after: np.ndarray, verdict: str
) -> None:
    found = implausible_finding(before.astype(np.int64), after.astype(np.int64))
    assert found.verdict == verdict and not found.paper_finding  # our check, outside the tally


def test_pairwise_stats_are_the_mean_and_sd_of_scipys_cosine_distances() -> None:
    faces = RNG.uniform(0, 1, (2, 12, 7))
    got = pairwise_stats(faces)
    for k in range(2):
        d = pdist(faces[k], metric="cosine")
        assert got[k] == pytest.approx([d.mean(), d.std(ddof=1)])


def test_group_p_is_the_least_favourable_one_sided_p() -> None:
    nulls = (RNG.normal(0, 1, (99, 2)), RNG.normal(1, 1, (99, 2)))
    t = GroupTest("k", np.array([1.5, 0.0]), nulls)
    loop = [
        max((1 + sum(v >= t.observed[s] for v in n[:, s])) / 100 for n in nulls) for s in (0, 1)
    ]
    assert t.p == pytest.approx(loop)
    assert t.flagged == (min(loop) < ALPHA / 2)


def group_tests(flags: dict[str, list[bool]]) -> list[GroupTest]:
    null = (np.tile([0.2, 0.05], (99, 1)) + np.linspace(0, 0.01, 99)[:, None],)
    out = []
    for kind, fs in flags.items():
        out += [GroupTest(kind, np.array([0.5 if f else 0.2, 0.05]), null) for f in fs]
    return out


DENSE, SPARSE, MIXED = KINDS


@pytest.mark.parametrize(
    ("flags", "verdict"),
    [
        ({DENSE: [False] * 60, SPARSE: [False] * 60, MIXED: [True] * 60}, "holds"),
        # the mixtures found only partly: the point (no false alarms) holds
        ({DENSE: [False] * 60, SPARSE: [False] * 60, MIXED: [True] * 40 + [False] * 20}, "partly"),
        # one kind of one-target group flagged, the rest as claimed: the parts disagree
        ({DENSE: [False] * 60, SPARSE: [True] * 60, MIXED: [True] * 60}, "partly"),
        ({DENSE: [True] * 60, SPARSE: [True] * 60, MIXED: [False] * 60}, "differs"),
        ({DENSE: [False] * 3, SPARSE: [False] * 3, MIXED: [True] * 2 + [False]}, "inconclusive"),
    ],
)
def test_intersample_rule_reaches_each_verdict(flags: dict[str, list[bool]], verdict: str) -> None:
    tests = group_tests(flags)
    assert [t.flagged for t in tests] == [f for fs in flags.values() for f in fs]
    assert intersample_finding(tests, "known").verdict == verdict
