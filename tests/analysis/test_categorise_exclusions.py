"""The exclusion rule's categorisation criteria (issue #39, report item 7) on a simulated study
export (an evolve block, then a categorise block of the participants' own and others' faces):
nobody is excluded as it was simulated (with plausible browser response times written in), and
each planted participant — one answer throughout, every answer wrong, answers at 150 ms — is
excluded for that criterion alone, counted against a plain loop over the responses table.
"""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest

from emogen.analysis.exclusions import REASONS, ExclusionRule, apply_exclusions, rule_from_options
from emogen.analysis.flow import CRITERIA
from emogen.analysis.people import load_people
from tests.analysis.test_analyse_people import _export as simulated_export

STUDY: dict[str, Any] = {
    "name": "labels",
    "emotions": ["happy", "sad", "angry", "fearful"],
    "seed": 8,
    "ga": {"generations": 2, "min_selections": 1, "max_selections": 5},
    "blocks": [
        {"task": "evolve"},
        {"task": "categorise", "own": True, "others": 8, "none_option": True},
    ],
}
CAT_FLAGS = ["one_label", "at_chance", "fast_labels"]


@pytest.fixture(scope="module")
def export(ict_model, tmp_path_factory: pytest.TempPathFactory) -> Path:  # type: ignore[no-untyped-def]
    root = simulated_export(tmp_path_factory.mktemp("labels"), ict_model, 6, STUDY)
    # browser response times as people take them (log-normal around 2 s), not simulated ones
    path = root / "categorise_responses.parquet"
    r = pd.read_parquet(path)
    rng = np.random.default_rng(5)
    r["client_response_ms"] = np.exp(rng.normal(np.log(2000), 0.4, len(r)))
    r.to_parquet(path)
    return root


def plant(export: Path, out: Path, who: dict[str, str]) -> None:
    """A copy of ``export`` with ``who[pid]`` ('one_label', 'at_chance', 'fast_labels')."""
    shutil.copytree(export, out)
    path = out / "categorise_responses.parquet"
    r = pd.read_parquet(path)
    for pid, kind in who.items():
        mine = r["participant_id"] == pid
        if kind == "one_label":
            r.loc[mine, "label"] = "sad"
        elif kind == "at_chance":  # always a wrong label, spread over the others
            for i in np.flatnonzero(mine):
                offered = str(r.at[i, "labels"]).split("|")
                meant = r.at[i, "intended"]
                wrong = [x for x in offered if pd.isna(meant) or x != meant]
                r.at[i, "label"] = wrong[i % len(wrong)]
        else:
            r.loc[mine, "client_response_ms"] = 150.0
        scored = mine & r["intended"].notna()
        r.loc[scored, "correct"] = r.loc[scored, "label"] == r.loc[scored, "intended"]
    r.to_parquet(path)


def plain_flags(export: Path) -> dict[str, set[str]]:
    """Each criterion by a loop over the responses (defaults: 0.9, chance, 400 ms, 10)."""
    rows = pd.read_parquet(export / "categorise_responses.parquet").to_dict("records")
    per: dict[str, list[dict[str, Any]]] = {}
    for row in rows:
        if not pd.isna(row["label"]):
            per.setdefault(str(row["participant_id"]), []).append(row)
    out: dict[str, set[str]] = {k: set() for k in CAT_FLAGS}
    for pid, mine in per.items():
        labels = [row["label"] for row in mine]
        top = max(labels.count(x) for x in set(labels))
        if len(mine) >= 10 and top / len(mine) > 0.9:
            out["one_label"].add(pid)
        scored = [row for row in mine if not pd.isna(row["intended"])]
        hits = sum(row["label"] == row["intended"] for row in scored)
        chance = sum(1 / len(row["labels"].split("|")) for row in scored)
        if len(scored) >= 10 and hits <= chance:
            out["at_chance"].add(pid)
        if float(np.median([row["client_response_ms"] for row in mine])) < 400:
            out["fast_labels"].add(pid)
    return out


def test_every_criterion_has_its_flow_line() -> None:
    assert set(CRITERIA) == set(REASONS)


def test_nobody_is_excluded_as_simulated(export: Path) -> None:
    people = load_people(export)
    _, table = apply_exclusions(people, ExclusionRule())
    assert not table["excluded"].any(), table
    assert (table["cat_answers"] >= 12).all()  # 4 own + 8 others' faces each
    assert (table["cat_accuracy"] > table["cat_chance"] + 0.2).all(), table
    assert plain_flags(export) == {k: set() for k in CAT_FLAGS}


def test_each_planted_participant_is_excluded_for_it(export: Path, tmp_path: Path) -> None:
    ids = sorted(load_people(export).faces["participant_id"].astype(str).unique())
    # the last to arrive has the most faces of others scored (the first ones had fallbacks)
    who = {ids[0]: "one_label", ids[-1]: "at_chance", ids[1]: "fast_labels"}
    plant(export, tmp_path / "planted", who)
    _, table = apply_exclusions(load_people(tmp_path / "planted"), ExclusionRule())
    table = table.set_index("participant_id")
    plain = plain_flags(tmp_path / "planted")
    for pid, kind in who.items():
        assert plain[kind] == {pid}
        flagged = [c for c in CAT_FLAGS if table.at[pid, c]]
        assert flagged == [kind], (pid, kind, flagged)
        assert table.at[pid, "excluded"]
    assert set(table.index[table["excluded"]]) == set(who)
    reasons = table.at[ids[-1], "reasons"]
    assert reasons.startswith("categorise accuracy 0% (chance"), reasons
    # switched off, or a threshold changed, on the command line's terms
    rule = rule_from_options(["max_categorise_label_share=none", "min_categorise_median_rt_ms=100"])
    _, table = apply_exclusions(load_people(tmp_path / "planted"), rule)
    assert set(table.loc[table["excluded"], "participant_id"]) == {ids[-1]}
    text = "; ".join(rule.describe())
    assert "categorise accuracy <= chance" in text and "one categorise answer" not in text


def test_wrong_categorise_thresholds_are_named() -> None:
    with pytest.raises(Exception, match="max_categorise_label_share"):
        ExclusionRule(max_categorise_label_share=1.5)
    with pytest.raises(Exception, match="min_categorise_answers needs a number"):
        rule_from_options(["min_categorise_answers=none"])
