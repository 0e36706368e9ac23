"""Own expressions and recognition accuracy (emogen.analysis.fields_accuracy): the measures
against plain loops over the export's tables, r against scipy, and known answers on planted
studies (benchmarks/planted_study.py): found when participants label by their own prototypes
and some people's emotions lie closer together; held at α when labels ignore the faces."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from benchmarks.planted_study import PlantedDesign, write_planted_study
from scipy import stats

from emogen.analysis.fields_accuracy import distinctness_accuracy, participant_measures
from emogen.analysis.people import load_people


def _people(tmp_path, seed: int, **kw):  # type: ignore[no-untyped-def]
    return load_people(write_planted_study(PlantedDesign(**kw), tmp_path / f"s{seed}", seed=seed))


def test_measures_are_plain_loops_over_the_export(tmp_path) -> None:  # type: ignore[no-untyped-def]
    people = _people(tmp_path, 1, participants=9, repetitions=2, distinctness_sd=0.5)
    got = participant_measures(people).set_index("participant_id")
    genes = list(people.genes)
    for pid in ("P000", "P004"):
        mine = people.faces[people.faces["participant_id"] == pid]
        means = [
            [sum(mine.loc[mine["emotion"] == e, g]) / (mine["emotion"] == e).sum() for g in genes]
            for e in sorted(set(mine["emotion"]))
        ]
        pairs = list(itertools.combinations(means, 2))
        assert got.loc[pid, "distinctness"] == pytest.approx(
            sum(math.dist(a, b) for a, b in pairs) / len(pairs), rel=1e-12
        )
        answers = [
            r
            for r in people.responses.itertuples()
            if r.participant_id == pid and r.source == "other"
        ]
        hits = sum(r.label == r.intended for r in answers)
        assert got.loc[pid, "accuracy"] == pytest.approx(hits / len(answers))
        assert got.loc[pid, "n_answers"] == len(answers)


def test_a_planted_relation_is_found(tmp_path) -> None:  # type: ignore[no-untyped-def]
    for seed in range(3):
        people = _people(tmp_path, seed, participants=40, own_weight=1.0, distinctness_sd=0.6)
        res = distinctness_accuracy(people, rng=np.random.default_rng(seed), permutations=999)
        assert res["status"] == "ok" and res["r"] > 0 and res["p_perm"] < 0.05, res
        table = res["table"]
        ref = stats.pearsonr(table["distinctness"], table["accuracy"])
        assert res["r"] == pytest.approx(ref.statistic, rel=1e-12)
        assert res["ci_low"] < res["r"] < res["ci_high"]


def test_labels_that_ignore_the_faces_hold_alpha(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """20 null studies: at most 2 rejections at α = 0.05 (α + 2 SE = 0.147 of 20: 2.9)."""
    rejected = 0
    for seed in range(20):
        people = _people(
            tmp_path, 50 + seed, participants=16, labelling="ignore_faces", distinctness_sd=0.6
        )
        res = distinctness_accuracy(people, rng=np.random.default_rng(seed), permutations=199)
        rejected += res["p_perm"] <= 0.05
    assert rejected <= 2


def test_too_few_participants_is_a_reason_not_a_number(tmp_path) -> None:  # type: ignore[no-untyped-def]
    res = distinctness_accuracy(
        _people(tmp_path, 3, participants=6), rng=np.random.default_rng(0), permutations=9
    )
    assert res["status"] == "failed" and "needs 8" in res["reason"] and res["r"] is None
