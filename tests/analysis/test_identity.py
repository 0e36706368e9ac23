"""Identity effects within participants: distances against a plain loop, the within/between
test against planted identity shifts (found) and their absence (false-positive rate), and
cross-identity decoding against chance."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from benchmarks.calibrate_known_answers import IDENTITY, IDENTITY_SHIFT

from emogen.analysis import identity
from emogen.analysis.analyse_options import AnalysisOptions
from emogen.analysis.identity import (
    cross_identity_decoding,
    identity_distances,
    identity_section,
    within_between_test,
)
from emogen.analysis.results import write_analysis
from emogen.analysis.simulated_study import PeopleDesign, as_people, simulate_people

ALPHA = 0.05


@pytest.fixture(scope="module")
def rig(ict_model):  # type: ignore[no-untyped-def]
    return ict_model.rig


def _design(participants: int, shifted: bool = False) -> PeopleDesign:
    """Happy and sad, 2 repetitions; ``shifted``: IDENTITY_SHIFT's happy and sad genes."""
    shift = {e: IDENTITY_SHIFT["male-medium"][e] for e in ("happy", "sad")}
    return PeopleDesign(
        participants=participants,
        emotions=("happy", "sad"),
        repetitions=2,
        categorise=False,
        identity_shifts={"male-medium": shift} if shifted else {},
    )


def test_distances_match_a_plain_loop(rig) -> None:  # type: ignore[no-untyped-def]
    people = as_people(simulate_people(_design(3), rig, seed=1))
    table = identity_distances(people)
    f = people.faces
    for row in table.itertuples():
        mine = f[(f["participant_id"] == row.participant_id) & (f["emotion"] == row.emotion)]
        same, diff = [], []
        recs = list(mine.itertuples())
        for i in range(len(recs)):
            for j in range(i + 1, len(recs)):
                a = np.array([getattr(recs[i], g) for g in people.genes])
                b = np.array([getattr(recs[j], g) for g in people.genes])
                d = float(np.sqrt(((a - b) ** 2).sum()))
                (same if recs[i].identity == recs[j].identity else diff).append(d)
        assert row.within == pytest.approx(np.mean(same))
        assert row.between == pytest.approx(np.mean(diff))
        assert (row.n_within, row.n_between) == (len(same), len(diff))


def test_planted_identity_shift_is_found(rig) -> None:  # type: ignore[no-untyped-def]
    """50 participants × 4 emotions × 3 repetitions, a shift on every emotion: found at 40 of
    40 fresh seeds on rig 3 (30 × 2 emotions × 2 repetitions: 21 of 40;
    ``python -m benchmarks.calibrate_known_answers --checks identity``)."""
    people = as_people(simulate_people(IDENTITY, rig, seed=2))
    r = within_between_test(identity_distances(people), rng=np.random.default_rng(0))
    assert r["difference"] > 0 and r["ci_low"] > 0 and r["p"] < ALPHA
    assert r["p_sign_flip"] < ALPHA


def test_false_positive_rate_without_identity_effect(rig) -> None:  # type: ignore[no-untyped-def]
    """100 null studies: rejections at most the binomial 99.9% quantile (13 of 100), which a test
    at α passes with probability 0.999 and one at 0.2 fails with 0.95 (a bound of α + 2 SE over 30 studies failed good data 1
    time in 16). Over 2000 fresh seeds (10000-11999) the rate was 0.0525 on rig 2 and 0.0485 on
    rig 1; benchmarks/calibrate_fields.py has its own run."""
    from scipy.stats import binom

    k = 100
    rejected = 0
    for s in range(k):
        people = as_people(simulate_people(_design(16), rig, seed=1000 + s))
        r = within_between_test(
            identity_distances(people), rng=np.random.default_rng(s), n_perm=999
        )
        rejected += r["p"] < ALPHA
    assert rejected <= binom.ppf(0.999, k, ALPHA), rejected


def test_emotion_decodes_across_identities(rig) -> None:  # type: ignore[no-untyped-def]
    people = as_people(simulate_people(_design(20), rig, seed=3))
    dec = cross_identity_decoding(people, rng=np.random.default_rng(0), n_perm=19)
    cross = dec[dec["cross"]]
    assert len(cross) == 2  # both directions
    assert (cross["accuracy"] > cross["null_95"]).all() and (cross["p"] <= 0.05).all()
    assert (cross["chance"].between(0.35, 0.65)).all()  # two emotions: chance ≈ 1/2
    assert (cross["accuracy"] > 0.8).all()


def test_decoding_without_emotion_information_is_at_chance(rig) -> None:  # type: ignore[no-untyped-def]
    people = as_people(simulate_people(_design(12), rig, seed=4))
    rng = np.random.default_rng(5)
    f = people.faces.copy()
    f["emotion"] = rng.permutation(f["emotion"].to_numpy())  # labels carry nothing
    from dataclasses import replace

    dec = cross_identity_decoding(replace(people, faces=f), rng=rng, n_perm=19)
    assert (dec["accuracy"] < 0.75).all()


def test_identity_section_skips_one_identity_and_writes_tables(
    rig, tmp_path: Path, monkeypatch
) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.setattr(identity, "DECODING_PERMUTATIONS", 19)
    one = PeopleDesign(participants=4, identities=("female-medium",), categorise=False)
    report = identity_section(
        as_people(simulate_people(one, rig, seed=1)), tmp_path / "a", AnalysisOptions(), None
    )
    assert "Skipped: every face was made on one identity" in (
        write_analysis("t", report.out, [report], {})[1].read_text()
    )
    people = as_people(simulate_people(_design(8), rig, seed=2))
    report = identity_section(people, tmp_path / "b", AnalysisOptions(), None)
    summary = report.data
    write_analysis("t", report.out, [report], {})
    for name in ("identity_distances", "identity_distance_test", "identity_decoding"):
        assert (tmp_path / "b" / "tables" / f"{name}.csv").is_file()
    assert {"distance", "decoding"} <= set(summary["identity"])


def test_decoding_equals_one_fit_per_ordered_pair(rig) -> None:  # type: ignore[no-untyped-def]
    """The decoding table (one LDA per fold and training identity, shared by the identities it
    is tested on) equals a plain loop that fits one LDA per ordered pair and fold, with the
    same folds and the same shuffles."""
    from itertools import permutations

    import pandas as pd
    from sklearn.discriminant_analysis import LinearDiscriminantAnalysis

    people = as_people(simulate_people(_design(10, True), rig, seed=6))
    n_perm = 5
    dec = cross_identity_decoding(people, rng=np.random.default_rng(8), n_perm=n_perm)

    f = people.faces.reset_index(drop=True)
    x, y = people.gene_matrix(f), f["emotion"].astype(str).to_numpy()
    who = f["participant_id"].astype(str).to_numpy()
    ident = f["identity"].astype(str).to_numpy()
    ids = sorted(set(ident))
    rng = np.random.default_rng(8)  # the same draws, in the same order
    order = rng.permutation(np.array(sorted(set(who))))
    folds = [a for a in np.array_split(order, min(5, len(order))) if len(a)]
    pairs = [*permutations(ids, 2), *((i, i) for i in ids)]

    def accuracy(labels: np.ndarray, a: str, b: str) -> float:
        shares = []
        for test in folds:
            held = np.isin(who, test)
            train, target = ~held & (ident == a), held & (ident == b)
            fit = LinearDiscriminantAnalysis(solver="lsqr", shrinkage="auto")
            fit.fit(x[train], labels[train])
            for p in np.unique(who[target]):
                mine = target & (who == p)
                shares.append(float(np.mean(fit.predict(x[mine]) == labels[mine])))
        return float(np.mean(shares))

    cells = pd.Series([f"{w}\x00{i}" for w, i in zip(who, ident, strict=True)])
    null = {pair: [] for pair in pairs}
    for _ in range(n_perm):
        shuffled = y.copy()
        for idx in pd.Series(np.arange(len(y))).groupby(cells.to_numpy()).indices.values():
            shuffled[idx] = y[rng.permutation(idx)]
        for a, b in pairs:
            null[(a, b)].append(accuracy(shuffled, a, b))
    assert list(zip(dec["train_identity"], dec["test_identity"], strict=True)) == pairs
    for row in dec.to_dict("records"):
        pair = (row["train_identity"], row["test_identity"])
        assert row["accuracy"] == pytest.approx(accuracy(y, *pair), abs=1e-12)
        assert row["chance"] == pytest.approx(np.mean(null[pair]), abs=1e-12)
