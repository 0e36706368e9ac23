"""Condition tests (repeated-measures permutation MANOVA): the pseudo-F against statsmodels'
AnovaRM for one outcome, p against plain-loop enumeration, calibration at α on null data and
power on a planted identity effect."""

from __future__ import annotations

import itertools

import numpy as np
import pandas as pd
import pytest
from statsmodels.stats.anova import AnovaRM

from emogen.analysis.conditions import condition_tests, within_permutation_test
from emogen.analysis.simulated_study import PeopleDesign, as_people, simulate_people
from emogen.tasks.simulated import SimulatedDesign


def test_pseudo_f_is_the_repeated_measures_f_for_one_outcome() -> None:
    rng = np.random.default_rng(0)
    y = rng.normal(0, 1, (9, 3, 1)) + np.array([0.0, 0.5, 1.0])[None, :, None]
    f, *_ = within_permutation_test(y, permutations=10, rng=rng)
    long = pd.DataFrame(
        [(i, k, y[i, k, 0]) for i in range(9) for k in range(3)], columns=["p", "c", "y"]
    )
    ref = AnovaRM(long, "y", "p", within=["c"]).fit().anova_table["F Value"].iloc[0]
    assert f == pytest.approx(ref)


def test_permutation_p_matches_plain_enumeration() -> None:
    rng = np.random.default_rng(2)
    y = rng.normal(0, 1, (4, 3, 2))
    y[:, 2] += 0.7
    f, p, eta, b, exact = within_permutation_test(y, permutations=5000, rng=rng)
    assert exact and b == 6**4

    def plain_f(z: np.ndarray) -> float:
        n, k = z.shape[:2]
        zc = z - z.mean(axis=1, keepdims=True)
        means = zc.mean(axis=0)
        ss_eff = sum(n * float(means[j] @ means[j]) for j in range(k))
        ss_err = sum(
            float((zc[i, j] - means[j]) @ (zc[i, j] - means[j])) for i in range(n) for j in range(k)
        )
        return (ss_eff / (k - 1)) / (ss_err / ((k - 1) * (n - 1)))

    null = [
        plain_f(np.stack([y[i, list(o[i])] for i in range(4)]))
        for o in itertools.product(itertools.permutations(range(3)), repeat=4)
    ]
    assert f == pytest.approx(plain_f(y))
    assert p == pytest.approx(np.mean(np.array(null) >= f * (1 - 1e-9)))
    assert 0 < eta < 1


@pytest.fixture(scope="module")
def rig(ict_model):  # type: ignore[no-untyped-def]
    return ict_model.rig


BASE = PeopleDesign(
    emotions=("happy", "sad"),
    participants=20,
    repetitions=1,
    categorise=False,
    participant=SimulatedDesign(spread=0.1),
)


def test_identity_tests_hold_alpha_on_null_and_find_a_planted_effect(rig) -> None:  # type: ignore[no-untyped-def]
    """20 null studies (identities make no difference): identity and interaction rejected in
    at most 4 each (α = 0.05; P(≥ 5) ≈ 0.003); a planted identity shift on three genes of both
    emotions (main effect, no interaction) found."""
    hits = {"identity": 0, "emotion × identity": 0}
    for seed in range(20):
        people = as_people(simulate_people(BASE, rig, seed=200 + seed))
        t = condition_tests(
            people, permutations=500, bootstrap=50, level=0.95, rng=np.random.default_rng(seed)
        ).set_index("effect")
        assert t.loc["emotion", "p_perm"] < 0.01  # happy and sad differ
        for k in hits:
            hits[k] += bool(t.loc[k, "p_perm"] < 0.05)
    assert max(hits.values()) <= 4, hits
    shift = {"mouthSmile": 0.5, "browInnerUp": 0.5, "eyeWide": 0.5}
    planted = PeopleDesign(
        **{**BASE.__dict__, "identity_shifts": {"male-medium": {"happy": shift, "sad": shift}}}
    )
    people = as_people(simulate_people(planted, rig, seed=5))
    t = condition_tests(
        people, permutations=500, bootstrap=200, level=0.95, rng=np.random.default_rng(0)
    ).set_index("effect")
    assert t.loc["identity", "p_perm"] < 0.05
    assert t.loc["identity", "ci_low"] > 0
