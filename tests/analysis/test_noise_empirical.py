"""The empirical null of the spread test: between-participant against within-participant spread
of repeated faces. Figures against plain loops (scipy's cosine distance); known answers on
simulated studies with repetitions (emogen.analysis.simulated_study): one shared prototype
(participant spread 0) is flagged at most at α + 2 SE, participants with their own prototypes
are flagged.

Monte Carlo tolerance: K independent tests, each flagged with probability ≤ α under H0: the
flagged share has SE sqrt(α(1 − α)/K); K = 60 (30 studies × 2 emotions): bound α + 2 SE =
0.106 (6 of 60).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.distance import cosine

from emogen.analysis.noise_empirical import empirical_spread_test, has_repeats
from emogen.analysis.simulated_study import PeopleDesign, simulate_people
from emogen.errors import DataError
from emogen.tasks.simulated import SimulatedDesign

ALPHA = 0.05


def _plain(x: np.ndarray, who: np.ndarray) -> tuple[float, float]:
    within, between = [], []
    for a in range(len(x)):
        for b in range(a + 1, len(x)):
            (within if who[a] == who[b] else between).append(cosine(x[a], x[b]))
    return float(np.mean(within)), float(np.mean(between))


def test_figures_against_plain_loops() -> None:
    rng = np.random.default_rng(0)
    people = np.repeat(np.arange(6), 3)
    x = np.abs(rng.normal(size=(6, 8)))[people] + 0.3 * np.abs(rng.normal(size=(18, 8)))
    who = np.array([f"p{i}" for i in people])
    res = empirical_spread_test(x, who, permutations=199, rng=np.random.default_rng(1))
    within, between = _plain(x, who)
    assert res.within == pytest.approx(within) and res.between == pytest.approx(between)
    # balanced design: the moment estimate of σ²_b is between − within in CD units
    assert res.excess == pytest.approx(between - within)
    assert res.excess_lo < res.excess < res.excess_hi
    # the permutation p by a plain loop: the same permutations, labels moved with the faces
    perm_rng, count = np.random.default_rng(1), 0
    for _ in range(199):
        perm = perm_rng.permutation(len(x))
        moved = np.empty_like(who)
        moved[perm] = who
        w, b = _plain(x, moved)
        count += (b - w) >= (between - within) - 1e-12
    assert res.p_value == pytest.approx((1 + count) / 200)
    assert res.p_value < 0.01 and res.exceeds  # 6 distinct people, small repeat noise


def test_neutral_faces_are_left_out_and_counted() -> None:
    """A neutral face has no direction: the test on the group with two neutral faces added
    equals the test without them (plain loops), and says how many it left out; a group whose
    repeats are neutral faces is refused."""
    rng = np.random.default_rng(3)
    people = np.repeat(np.arange(5), 3)
    x = np.abs(rng.normal(size=(5, 6)))[people] + 0.3 * np.abs(rng.normal(size=(15, 6)))
    who = np.array([f"p{i}" for i in people])
    with_neutral = np.vstack([x, np.zeros((2, 6))])
    who_neutral = np.concatenate([who, ["p0", "p9"]])
    res = empirical_spread_test(
        with_neutral, who_neutral, permutations=99, rng=np.random.default_rng(1)
    )
    within, between = _plain(x, who)
    assert res.neutral == 2 and res.faces == 15 and res.participants == 5
    assert res.within == pytest.approx(within) and res.between == pytest.approx(between)
    assert not has_repeats(np.array(["a", "a", "b", "b"]), np.array([[1.0], [0], [1], [1]]))
    with pytest.raises(DataError, match="neutral faces, which have no direction, not counted"):
        empirical_spread_test(
            np.array([[1.0, 0], [0, 0], [1, 1], [1, 2]]),
            np.array(["a", "a", "b", "b"]),
            rng=np.random.default_rng(0),
        )


def test_needs_two_participants_with_repeats() -> None:
    assert not has_repeats(np.array(["a", "a", "b"]))
    with pytest.raises(DataError, match="at least 2 participants with 2 or more"):
        empirical_spread_test(
            np.ones((3, 4)), np.array(["a", "a", "b"]), rng=np.random.default_rng(0)
        )


def _flagged(rig, spread: float, studies: int, n: int) -> list[bool]:  # type: ignore[no-untyped-def]
    design = PeopleDesign(
        emotions=("happy", "sad"),
        identities=("female-medium",),
        participants=n,
        repetitions=3,
        participant=SimulatedDesign(spread=spread),
        categorise=False,
    )
    out = []
    for k in range(studies):
        sim = simulate_people(design, rig, seed=100 + k)
        for emotion in design.emotions:
            f = sim.faces[sim.faces["emotion"] == emotion]
            res = empirical_spread_test(
                f[list(sim.weights)].to_numpy(),
                f["participant_id"].to_numpy(),
                permutations=199,
                rng=np.random.default_rng(k),
            )
            out.append(res.exceeds)
    return out


def test_one_shared_prototype_is_flagged_at_most_at_alpha(ict_model) -> None:  # type: ignore[no-untyped-def]
    flagged = _flagged(ict_model.rig, 0.0, studies=30, n=12)
    bound = ALPHA + 2 * np.sqrt(ALPHA * (1 - ALPHA) / len(flagged))
    assert np.mean(flagged) <= bound, f"{sum(flagged)} of {len(flagged)} flagged"


def test_participants_own_prototypes_are_flagged(ict_model) -> None:  # type: ignore[no-untyped-def]
    """The simulator's default individual differences (spread 0.5): nearly always found."""
    flagged = _flagged(ict_model.rig, 0.5, studies=5, n=12)
    assert np.mean(flagged) >= 0.9, f"{sum(flagged)} of {len(flagged)} flagged"
