"""Group comparisons of participants against plain-loop references and known answers."""

from __future__ import annotations

import numpy as np
import pytest

from emogen.analysis.groups import _dispersion_f, _r2, compare_groups, mean_faces
from emogen.analysis.simulated_study import PeopleDesign, as_people, simulate_people
from emogen.errors import DataError
from emogen.tasks.simulated import SimulatedDesign


def test_r2_and_dispersion_f_by_plain_loops() -> None:
    rng = np.random.default_rng(1)
    x = rng.normal(size=(17, 4))
    codes = np.array([0] * 5 + [1] * 7 + [2] * 5)
    grand = x.mean(0)
    ssb = sum(np.sum(codes == g) * np.sum((x[codes == g].mean(0) - grand) ** 2) for g in range(3))
    assert _r2(x, codes)[0] == pytest.approx(ssb / np.sum((x - grand) ** 2))
    z = rng.uniform(size=17)
    from scipy import stats

    ref = stats.f_oneway(*[z[codes == g] for g in range(3)]).statistic
    assert _dispersion_f(z, codes)[0] == pytest.approx(ref)


def _two_groups(
    rng: np.random.Generator, shift: float, sd_b: float = 1.0
) -> tuple[np.ndarray, np.ndarray]:
    a = rng.normal(0, 1, (15, 5))
    b = rng.normal(0, sd_b, (15, 5))
    b[:, 0] += shift
    return np.vstack([a, b]), np.array(["a"] * 15 + ["b"] * 15)


def test_false_positive_rates_at_alpha() -> None:
    """200 null data sets: location (same distribution) and dispersion (groups shifted in
    location, same spread) reject at α = 0.05 within 2 SE."""
    rng = np.random.default_rng(2)
    loc = disp = 0
    n = 200
    for _ in range(n):
        x, g = _two_groups(rng, 0.0)
        loc += compare_groups(x, g, rng=rng, permutations=499, draws=10)["p_location"] <= 0.05
        x, g = _two_groups(rng, 1.5)
        disp += compare_groups(x, g, rng=rng, permutations=499, draws=10)["p_dispersion"] <= 0.05
    bound = 0.05 + 2 * np.sqrt(0.05 * 0.95 / n)
    assert loc / n <= bound and disp / n <= bound, (loc / n, disp / n)


def test_effects_are_found() -> None:
    rng = np.random.default_rng(3)
    found_loc = found_disp = 0
    for _ in range(40):
        x, g = _two_groups(rng, 1.5)
        found_loc += compare_groups(x, g, rng=rng, permutations=499, draws=10)["p_location"] <= 0.05
        x, g = _two_groups(rng, 0.0, sd_b=2.0)
        found_disp += (
            compare_groups(x, g, rng=rng, permutations=499, draws=10)["p_dispersion"] <= 0.05
        )
    assert found_loc >= 36 and found_disp >= 30, (found_loc, found_disp)


def test_planted_group_effect_in_a_simulated_study(ict_model) -> None:  # type: ignore[no-untyped-def]
    design = PeopleDesign(
        participants=30,
        repetitions=2,
        identities=("female-medium",),
        categorise=False,
        groups=("control", "clinical"),
        shifts={"clinical": {"happy": {"browInnerUp": 0.7}}},
        participant=SimulatedDesign(spread=0.2),
    )
    people = as_people(simulate_people(design, ict_model.rig, seed=4))
    rng = np.random.default_rng(0)
    res = {}
    for emotion in ("happy", "sad"):
        m = mean_faces(people, emotion)
        assert len(m) == 30  # one row per participant, not per face
        res[emotion] = compare_groups(
            m[list(people.genes)].to_numpy(),
            m["group"].to_numpy(),
            rng=rng,
            permutations=999,
            draws=200,
        )
    assert res["happy"]["p_location"] <= 0.01
    assert res["happy"]["centroid_ed_low"] > 0.05
    assert res["sad"]["p_location"] > 0.01


def test_too_small_groups_are_refused() -> None:
    with pytest.raises(DataError, match="at least 3 participants"):
        compare_groups(
            np.zeros((4, 2)), np.array(["a", "a", "a", "b"]), rng=np.random.default_rng(0)
        )
