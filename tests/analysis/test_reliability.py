"""Test–retest reliability against independent references: statsmodels' MixedLM variance
components, plain loops over face pairs, and a simulated study whose true ICC is known."""

from __future__ import annotations

import itertools

import numpy as np
import pandas as pd
import pytest

from emogen.analysis.reliability import components, distances, icc_interval, split_half
from emogen.analysis.simulated_study import PeopleDesign, simulate_people
from emogen.errors import DataError


def _faces(
    n: int, k: int, sb: float, sw: float, d: int, seed: int
) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    person = rng.normal(0, sb, (n, d))
    x = np.repeat(person, k, axis=0) + rng.normal(0, sw, (n * k, d))
    return x, np.repeat([f"p{i:02d}" for i in range(n)], k)


def test_components_equal_mixed_model_reml_per_dimension() -> None:
    """Balanced data: the ANOVA components of each dimension are MixedLM's REML ones, and the
    multivariate components are their sums."""
    import statsmodels.formula.api as smf

    x, who = _faces(30, 4, 1.0, 0.8, 3, seed=1)
    within = between = 0.0
    for j in range(3):
        frame = pd.DataFrame({"y": x[:, j], "p": who})
        fit = smf.mixedlm("y ~ 1", frame, groups=frame["p"]).fit(reml=True)
        between += float(fit.cov_re.iloc[0, 0])
        within += float(fit.scale)
    c = components(x, who)
    assert c.within == pytest.approx(within, rel=1e-4)
    assert c.between == pytest.approx(between, rel=1e-4)
    assert c.icc == pytest.approx(between / (between + within), rel=1e-4)


def test_icc_is_one_minus_within_over_between_squared_distances() -> None:
    """Plain loops over every pair of faces (unbalanced: 2 to 5 faces per participant)."""
    rng = np.random.default_rng(2)
    sizes = rng.integers(2, 6, 25)
    who = np.repeat([f"p{i}" for i in range(25)], sizes)
    x = np.repeat(rng.normal(0, 1, (25, 4)), sizes, axis=0) + rng.normal(0, 1, (len(who), 4))
    ssw = sum(np.sum((x[who == p] - x[who == p].mean(0)) ** 2) for p in np.unique(who))
    sst = np.sum((x - x.mean(0)) ** 2)
    n, big_n = 25, len(x)
    k0 = (big_n - np.sum(sizes**2) / big_n) / (n - 1)
    s2w = ssw / (big_n - n)
    s2b = ((sst - ssw) / (n - 1) - s2w) / k0
    c = components(x, who)
    assert c.within == pytest.approx(s2w) and c.between == pytest.approx(s2b)
    assert c.icc == pytest.approx(s2b / (s2b + s2w))


def test_distances_by_plain_loop() -> None:
    x, who = _faces(6, 3, 1.0, 0.5, 2, seed=3)
    table = distances(x, who).set_index("participant_id")
    for p in np.unique(who):
        mine, others = x[who == p], x[who != p]
        within = np.mean([np.linalg.norm(a - b) for a, b in itertools.combinations(mine, 2)])
        between = np.mean([np.linalg.norm(a - b) for a in mine for b in others])
        assert table.loc[p, "within"] == pytest.approx(within)
        assert table.loc[p, "between"] == pytest.approx(between)


@pytest.mark.parametrize("n", [12, 40])
def test_interval_covers_a_known_icc(n: int) -> None:
    """Gaussian faces with true ICC = 0.5 (dimensions of unequal variance): the 95% interval
    covers it in 95% of 300 data sets within 2 SE — at n = 12 too, where a bootstrap over
    participants covers only ~75%."""
    hits = []
    for s in range(300):
        x, who = _faces(n, 3, 1.0, 1.0, 8, seed=100 + s)
        x = x * np.linspace(2.0, 0.2, 8)
        lo, hi = icc_interval(x, who)
        hits.append(lo <= 0.5 <= hi)
    rate = np.mean(hits)
    assert abs(rate - 0.95) <= 2 * np.sqrt(0.95 * 0.05 / 300), rate


def test_split_half_finds_people_and_nothing_without_them() -> None:
    x, who = _faces(20, 4, 1.0, 0.3, 5, seed=4)
    rep = np.tile(np.arange(4), 20)
    strong = split_half(x, who, rep, rng=np.random.default_rng(0))
    assert strong["spearman_brown"] > 0.9 and strong["self_identification"] > 0.8
    assert strong["p_identification"] <= 0.01
    x0, _ = _faces(20, 4, 0.0, 1.0, 5, seed=5)
    null = split_half(x0, who, rep, rng=np.random.default_rng(0))
    assert abs(null["spearman_brown"]) < 0.6 and null["self_identification"] < 0.3


def test_a_design_without_repeats_is_refused() -> None:
    with pytest.raises(DataError, match="at least 2 participants with 2 or more faces"):
        components(np.zeros((4, 2)), np.array(["a", "b", "c", "d"]))


@pytest.mark.slow
def test_icc_interval_covers_the_simulated_truth(ict_model) -> None:  # type: ignore[no-untyped-def]
    """emogen's simulated participants (50 participants, 4 emotions, 2 identities, 3
    repetitions): the truth is the ICC of a 1000-participant, 4-repetition study of the same
    design (its own sampling SD ≈ 0.02); 20 studies × 8 cells = 160 intervals must cover it at
    ≥ 90% (nominal 95%; binomial SE 1.7 points) (the full 100-study run: benchmarks/calibrate_reliability.py)."""
    rig = ict_model.rig
    big = simulate_people(
        PeopleDesign(
            participants=1000, repetitions=4, identities=("female-medium",), categorise=False
        ),
        rig,
        seed=999,
    )
    truth = {
        e: components(f[list(big.genes)].to_numpy(), f["participant_id"].to_numpy()).icc
        for e, f in big.faces.groupby("emotion")
    }
    assert all(0.1 < t < 0.5 for t in truth.values()), truth  # a person effect to measure
    hits = []
    for s in range(20):
        sim = simulate_people(PeopleDesign(categorise=False), rig, seed=s)
        for (emotion, _), f in sim.faces.groupby(["emotion", "identity"]):
            lo, hi = icc_interval(f[list(sim.genes)].to_numpy(), f["participant_id"].to_numpy())
            hits.append(lo <= truth[emotion] <= hi)
    rate = float(np.mean(hits))
    assert rate >= 0.90, f"coverage {rate:.3f} of {len(hits)} intervals"


def test_interval_is_a_plain_jackknife_of_fishers_z() -> None:
    """The interval against a plain loop: one-way ANOVA mean squares summed over dimensions
    (unbalanced: k0 from the group sizes), z = ½ log(MSB / MSW) of the study without each
    participant in turn, pseudo-values' mean ± t(n − 1) SE, back by (F − 1) / (F + k0 − 1)."""
    from scipy import stats

    x, who = _faces(9, 3, 0.6, 1.0, 4, seed=21)
    keep = np.ones(len(who), dtype=bool)
    keep[[0, 5]] = False  # two participants with 2 faces: unbalanced
    x, who = x[keep], who[keep]
    people = np.unique(who)

    def z_and_k0(sel: np.ndarray) -> tuple[float, float]:
        xs, ws = x[sel], who[sel]
        groups = [xs[ws == p] for p in np.unique(ws)]
        n, total = len(groups), len(xs)
        grand = xs.mean(axis=0)
        ssb = sum(len(g) * np.sum((g.mean(axis=0) - grand) ** 2) for g in groups)
        ssw = sum(np.sum((g - g.mean(axis=0)) ** 2) for g in groups)
        k0 = (total - sum(len(g) ** 2 for g in groups) / total) / (n - 1)
        return 0.5 * np.log((ssb / (n - 1)) / (ssw / (total - n))), k0

    z, k0 = z_and_k0(np.ones(len(who), dtype=bool))
    pseudo = [len(people) * z - (len(people) - 1) * z_and_k0(who != p)[0] for p in people]
    half = stats.t.ppf(0.975, len(people) - 1) * np.std(pseudo, ddof=1) / np.sqrt(len(people))
    f = np.exp(2 * (np.mean(pseudo) + np.array([-half, half])))
    assert icc_interval(x, who) == pytest.approx(tuple((f - 1) / (f + k0 - 1)), rel=1e-9)
