"""The own-distance categorisation model (emogen.analysis.categorisation_models), against
independent references — statsmodels' ConditionalLogit and its formula GEE, distances by a plain
loop — and against known answers of simulated studies: the effect is found when participants
label with their own prototypes, and the test holds its α when they label with another's
(``shuffle_prototypes``: there distance to one's own faces still predicts labels through the
population prototype; only the contrast with another participant's faces is null)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from emogen.analysis import categorisation_fits as fits
from emogen.analysis import categorisation_models as cm
from emogen.analysis.categorisation_clogit import conditional_logit
from emogen.analysis.simulated_study import PeopleDesign, as_people, simulate_people

SMALL = dict(participants=20, repetitions=2, identities=("female-medium",))


@pytest.fixture(scope="module")
def rig(ict_model):  # type: ignore[no-untyped-def]
    return ict_model.rig


@pytest.fixture(scope="module")
def study(rig):  # type: ignore[no-untyped-def]
    """The planted study (benchmarks.calibrate_known_answers.OWN): 60 participants, where every
    check of the effect below holds at 39 of 40 fresh seeds on rig 3 (20 participants: 14 of
    40; ``python -m benchmarks.calibrate_known_answers --checks own``, docs/analysis.md)."""
    from benchmarks.calibrate_known_answers import OWN

    return as_people(simulate_people(OWN, rig, seed=11))


def test_conditional_logit_matches_statsmodels() -> None:
    from statsmodels.discrete.conditional_models import ConditionalLogit

    rng = np.random.default_rng(3)
    n, labels = 300, 4
    x = rng.normal(size=(n, labels, 2))
    avail = rng.uniform(size=(n, labels)) < 0.85
    avail[:, :2] = True
    util = np.where(avail, x @ np.array([-1.5, 0.7]), -np.inf) + rng.gumbel(size=(n, labels))
    chosen = np.argmax(util, axis=1)
    fit = conditional_logit(x, avail, chosen)
    assert fit.converged, fit.reason
    beta, info = fit.beta, fit.info
    rows, cols = np.nonzero(avail)
    ref = ConditionalLogit((chosen[rows] == cols).astype(float), x[rows, cols], groups=rows).fit(
        method="newton", maxiter=100, disp=False
    )
    assert beta == pytest.approx(ref.params, abs=1e-6)
    assert np.sqrt(np.diag(np.linalg.inv(info))) == pytest.approx(ref.bse, rel=1e-4)


def test_distances_are_to_the_mean_of_ones_own_faces(study) -> None:  # type: ignore[no-untyped-def]
    ans = cm.model_answers(study)
    assert not isinstance(ans, str)
    reference = cm.derangement(len(ans.participants), np.random.default_rng(0))
    table = cm.long_table(ans, reference)
    faces, shown = study.faces, study.responses.set_index(["participant_id", "trial"])
    genes = list(study.genes)
    for row in table.sample(40, random_state=1).itertuples():
        answer = shown.loc[(row.participant_id, row.trial)]
        assert answer["source"] in ("other", "random")  # never one's own face
        assert answer["source_participant_id"] != row.reference_participant_id
        assert row.chosen == (answer["label"] == row.label)
        face = [answer[g] for g in genes]
        for who, got in (
            (row.participant_id, row.d_own),
            (row.reference_participant_id, row.d_ref),
        ):
            mine = faces[(faces["participant_id"] == who) & (faces["emotion"] == row.label)]
            mean = [sum(mine[g]) / len(mine) for g in genes]
            assert got == pytest.approx(math.dist(face, mean), abs=1e-12)
    # every usable answer offers all four labels and chose one of them
    per = table.groupby(["participant_id", "answer"])
    assert (per["chosen"].sum() == 1).all() and (per.size() == 4).all()
    # every answer to a face one did not make is in, but for those the reference made
    others = study.responses[study.responses["source"] != "own"]
    ref_of = dict(zip(table["participant_id"], table["reference_participant_id"], strict=False))
    by_ref = others["source_participant_id"] == others["participant_id"].map(ref_of)
    assert per.ngroups == len(others) - int(by_ref.sum()) and by_ref.sum() > 0


def test_gee_matches_statsmodels_formula_gee(study) -> None:  # type: ignore[no-untyped-def]
    import statsmodels.api as sm
    import statsmodels.formula.api as smf

    ans = cm.model_answers(study)
    assert not isinstance(ans, str)
    table = cm.long_table(ans, cm.derangement(len(ans.participants), np.random.default_rng(4)))
    got = fits.gee_contrast(table)
    ref = smf.gee(
        "chosen ~ d_own + d_ref + C(label)",
        groups="participant_id",
        data=table,
        family=sm.families.Binomial(),
        cov_struct=sm.cov_struct.Exchangeable(),
    ).fit()
    assert got["slope_own"] == pytest.approx(ref.params["d_own"], rel=1e-5)
    assert got["slope_ref"] == pytest.approx(ref.params["d_ref"], rel=1e-5)
    assert got["se_own"] == pytest.approx(ref.bse["d_own"], rel=1e-4)
    contrast = ref.t_test("d_own - d_ref = 0")
    assert got["contrast"] == pytest.approx(float(contrast.effect[0]), rel=1e-5)
    assert got["p"] == pytest.approx(float(contrast.pvalue), rel=1e-3)
    assert got["odds_ratio_own"] == pytest.approx(math.exp(ref.params["d_own"]), rel=1e-5)


def test_the_own_distance_effect_is_found_when_present(study) -> None:  # type: ignore[no-untyped-def]
    res = cm.own_distance(study, rng=np.random.default_rng(1), n_shuffles=99)
    assert isinstance(res, cm.OwnDistance)
    assert res.primary["status"] == "ok" and res.primary["contrast"] < 0
    assert res.primary["p"] == res.control["p"] and res.primary["p_two_way"] < 1e-3
    assert res.gee["contrast"] < 0 and res.gee["p"] < 1e-3
    assert res.two_stage["mean_contrast"] < 0 and res.two_stage["p_t"] < 1e-3
    assert res.control["p"] <= 0.02 and res.control["slope_own"] < res.control["control_low"]
    assert len(res.slopes) == res.gee["n_participants"] == res.primary["n_participants"] == 60


def test_the_contrast_holds_alpha_when_prototypes_are_shuffled(rig) -> None:  # type: ignore[no-untyped-def]
    """40 null studies of 20 participants: no test rejects at α = 0.05 in more than the binomial
    99.9% quantile (7 of 40: a test at α passes this with probability 0.999, one at 0.2 fails
    it with 0.56); distance to one's own faces alone — the naive test — is 'significant' in most
    of them (what the contrast with a reference guards against). The rates themselves, over 600
    fresh seeds (20000-20599), before #41's primary test: two-way t 0.050, GEE 0.065 (the
    sandwich estimator is slightly liberal at 20 clusters: why it is not the primary), two-stage
    0.035, control (now the primary test) 0.033."""
    from scipy.stats import binom

    design = PeopleDesign(**SMALL, shuffle_prototypes=True)  # type: ignore[arg-type]
    k = 40
    p, naive = [], []
    for seed in range(k):
        people = as_people(simulate_people(design, rig, seed=500 + seed))
        res = cm.own_distance(people, rng=np.random.default_rng(seed), n_shuffles=49)
        assert isinstance(res, cm.OwnDistance)
        p.append([res.primary["p_two_way"], res.gee["p"], res.two_stage["p_t"], res.primary["p"]])
        naive.append(res.primary["ci_high_own"] < 0)
    rejected = (np.array(p) <= 0.05).sum(axis=0)
    assert (rejected <= binom.ppf(0.999, k, 0.05)).all(), rejected
    assert np.mean(naive) > 0.8


def test_too_few_participants_is_one_line(rig) -> None:  # type: ignore[no-untyped-def]
    people = as_people(
        simulate_people(
            PeopleDesign(participants=4, repetitions=1, identities=("female-medium",)), rig, seed=2
        )
    )
    why = cm.own_distance(people, rng=np.random.default_rng(0))
    assert isinstance(why, str) and "needs at least 6" in why
    none = as_people(
        simulate_people(
            PeopleDesign(
                participants=8, repetitions=1, categorise=False, identities=("female-medium",)
            ),
            rig,
            seed=2,
        )
    )
    assert (
        cm.own_distance(none, rng=np.random.default_rng(0))
        == "no categorise answers (no categorise block, or nobody has reached it yet)"
    )
