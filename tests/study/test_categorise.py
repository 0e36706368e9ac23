"""The categorise task in a study: blocks of evolve and categorise trials through the service.

References are independent of the categorise code: a face's weights are checked against the
exported ``faces`` table (the final face of the evolve trial it came from) or the CSV file's
own cells; the labels offered against the block's labels; what the participant is told against
what the face was made for.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from sqlalchemy import func, select

from emogen.errors import ConfigError, DataError, SelectionError
from emogen.study.config import study_from_dict
from emogen.study.errors import StepConflict
from emogen.study.export import export_tables
from emogen.study.replay import replay_session
from emogen.study.sessions import StudyService
from emogen.study.storage import Store
from emogen.study.tables import TrialRow
from emogen.tasks.categorise.tables import ResponseRow, StimulusRow
from tests.study.drive import (
    categorise_body,
    do,
    new_key,
    run_to_end,
    service_caller,
    step_args,
    study_service,
)

LABELS = ["happy", "sad", "angry"]
MIXED: dict[str, Any] = {
    "name": "mixed",
    "seed": 77,
    "emotions": LABELS,
    "order": "fixed",
    "ga": {"generations": 1, "min_selections": 1, "max_selections": 3},
    "blocks": [
        {"task": "evolve", "name": "make", "identities": ["female-medium"]},
        {
            "task": "categorise",
            "name": "label",
            "own": True,
            "others": 3,
            "random": 2,
            "none_option": True,
            "intensity": True,
        },
    ],
}


@pytest.fixture
def mixed(db_url: str, ict_model: Any) -> Any:
    store = Store(db_url)
    yield study_service(study_from_dict(MIXED), store, ict_model)
    store.dispose()


def at_categorise(service: StudyService, participant: str) -> tuple[str, dict[str, Any]]:
    token, state = service.create_session(participant)
    state = run_to_end(
        state,
        service_caller(service, token),
        stop=lambda s: s["stage"] == "trial" and s["trial"]["task"] == "categorise",
    )
    return token, state


def test_a_mixed_study_shows_own_faces_and_stores_every_answer(mixed: StudyService) -> None:
    token, state = mixed.create_session("C-1")
    seen: list[dict[str, Any]] = []
    call = service_caller(mixed, token)
    while state["stage"] != "done":
        seen.append(state)
        state = run_to_end(state, call, stop=lambda s, was=state: s is not was)  # one step
    categorised = [s for s in seen if s["stage"] == "trial" and s["trial"]["task"] == "categorise"]
    assert len(categorised) == 3 + 3 + 2  # own (3 evolve trials), others, random
    for s in categorised:
        view = s["view"]
        assert sorted(view["labels"]) == sorted(LABELS)  # every label, in a drawn order
        assert "emotion" not in view and "emotion" not in s["trial"]  # never told
        assert s["trial"]["prompt"] == view["question"]
        assert (
            view["none_option"] and view["intensity"]["points"] == 7 and view["confidence"] is None
        )
    tables = export_tables(mixed.store)
    resp = tables["categorise_responses"]
    assert len(resp) == 8 and resp["label"].notna().all()
    assert list(resp["labels"]) == ["|".join(s["view"]["labels"]) for s in categorised]
    # the own faces are the participant's final faces, as the faces table recorded them
    faces, trials = tables["faces"], tables["trials"]
    w_cols = [c for c in faces.columns if c.startswith("w_")]
    own = resp[resp["source"] == "own"]
    assert len(own) == 3 and set(own["intended"]) == set(LABELS)
    for _, row in own.iterrows():
        made = trials[(trials["trial"] == row["source_trial"])].iloc[0]
        assert made["task"] == "evolve" and made["emotion"] == row["intended"]
        final = faces[
            (faces["trial"] == row["source_trial"]) & (faces["face_id"] == made["final_face_id"])
        ].iloc[-1]
        np.testing.assert_array_equal(final[w_cols].to_numpy(float), row[w_cols].to_numpy(float))
        assert row["correct"] == (row["label"] == row["intended"])
    # no other session was complete: the 'other' faces are fallbacks (random draws), said so
    assert resp.loc[resp["source"] == "other", "fallback"].all()
    assert resp.loc[resp["source"] == "random", "intended"].isna().all()
    assert set(trials["task"]) == {"evolve", "categorise"} and (trials["status"] == "done").all()
    assert list(trials["block_name"].unique()) == ["make", "label"]


def test_the_researcher_sees_a_categorise_trial_as_such(mixed: StudyService) -> None:
    """The dashboard's step of a session at a categorise trial: no generation of a GA."""
    from emogen.study.progress import progress_as_shown

    _token, state = at_categorise(mixed, "C-dash")
    line = next(x for x in progress_as_shown(mixed.store) if x["participant_id"] == "C-dash")
    trials = state["progress"]["trials"]
    assert line["step"] == f"trial {state['progress']['trial'] + 1} of {trials} · categorise"
    assert line["generation_shown"] is None


def test_others_faces_come_from_completed_sessions_balanced_over_labels(
    mixed: StudyService,
) -> None:
    first, state = mixed.create_session("C-first")
    run_to_end(state, service_caller(mixed, first))
    token, state = at_categorise(mixed, "C-second")
    run_to_end(state, service_caller(mixed, token))
    resp = export_tables(mixed.store)["categorise_responses"]
    second = resp[resp["participant_id"] == "C-second"]
    others = second[second["source"] == "other"]
    assert not others["fallback"].any()
    assert set(others["source_participant_id"]) == {"C-first"}
    assert sorted(others["intended"]) == sorted(LABELS)  # one per label: balanced
    own = second[second["source"] == "own"]
    assert set(own["source_participant_id"]) == {"C-second"}


def test_wrong_answers_are_refused_and_a_repeated_key_stores_one(mixed: StudyService) -> None:
    token, state = at_categorise(mixed, "C-bad")
    trial = state["progress"]["trial"]
    with pytest.raises(SelectionError, match=r"label must be one of .*none.*got 'surprised'"):
        do(mixed, "categorise", token, new_key(), trial=trial, label="surprised", intensity=3)
    with pytest.raises(SelectionError, match="intensity is required"):
        do(mixed, "categorise", token, new_key(), trial=trial, label=LABELS[0])
    with pytest.raises(SelectionError, match=r"intensity must be an integer in \[1, 7\]; got 9"):
        do(mixed, "categorise", token, new_key(), trial=trial, label=LABELS[0], intensity=9)
    with pytest.raises(SelectionError, match="does not ask for confidence"):
        do(
            mixed,
            "categorise",
            token,
            new_key(),
            trial=trial,
            label=LABELS[0],
            intensity=3,
            confidence=2,
        )
    with pytest.raises(StepConflict, match="is a categorise trial"):
        do(
            mixed,
            "select",
            token,
            new_key(),
            trial=trial,
            attempt=0,
            generation=0,
            elite=0,
            others=[],
        )
    with pytest.raises(StepConflict, match="request is for trial"):
        do(mixed, "categorise", token, new_key(), trial=trial + 1, label=LABELS[0], intensity=3)
    key = new_key()
    after = do(
        mixed, "categorise", token, key, trial=trial, label="none"
    )  # no intensity for "none"
    again = do(mixed, "categorise", token, key, trial=trial, label="none")
    assert again.get("replayed") and again["progress"] == after["progress"]
    with pytest.raises(StepConflict, match="already used for a different request"):
        do(mixed, "categorise", token, key, trial=trial, label=LABELS[1], intensity=2)
    with mixed.store.read() as db:
        assert db.scalar(select(func.count()).select_from(ResponseRow)) == 1
        assert db.scalar(select(ResponseRow.label)) == "none"


def test_an_evolve_step_on_a_categorise_trial_and_back_is_a_conflict(mixed: StudyService) -> None:
    token, state = mixed.create_session("C-order")
    state = do(mixed, "begin", token, new_key())
    with pytest.raises(
        StepConflict,
        match="trial 1 is an evolve trial: it takes select, restart or rate, not answer",
    ):
        do(mixed, "categorise", token, new_key(), trial=0, label=LABELS[0], intensity=1)
    assert state["trial"]["task"] == "evolve" and step_args(state)["trial"] == 0


def test_the_same_participant_and_seed_get_the_same_faces(ict_model: Any, tmp_path: Path) -> None:
    answers = []
    for k in range(2):
        store = Store(f"sqlite:///{tmp_path / f'db{k}.sqlite'}")
        svc = study_service(study_from_dict(MIXED), store, ict_model)
        token, state = at_categorise(svc, "C-same")
        run_to_end(state, service_caller(svc, token))
        resp = export_tables(store)["categorise_responses"]
        answers.append(resp.filter(regex="^(w_|g_|labels|source|intended|identity)"))
        store.dispose()
    pd.testing.assert_frame_equal(answers[0], answers[1])


def test_a_stimulus_file_shows_its_rows_on_their_identities(ict_model: Any, tmp_path: Path) -> None:
    csv = tmp_path / "stimuli.csv"
    csv.write_text(
        "label,identity,jawOpen,mouthSmile_L,mouthSmile_R\n"
        "happy,male-dark,0.1,0.8,0.8\nsad,,0.0,0.0,0.0\nangry,female-light,0.5,0.2,0.2\n"
    )
    cfg = study_from_dict(
        {
            "name": "file",
            "emotions": LABELS,
            "seed": 3,
            "identities": ["generic", "male-dark", "female-light"],
            "blocks": [{"task": "categorise", "file": str(csv)}],
        }
    )
    store = Store(f"sqlite:///{tmp_path / 'file.sqlite'}")
    svc = study_service(cfg, store, ict_model)
    assert svc.n_trials == 3  # every row of the file
    token, state = svc.create_session("F-1")
    run_to_end(state, service_caller(svc, token))
    resp = export_tables(store)["categorise_responses"].sort_values("source_row")
    assert list(resp["intended"]) == ["happy", "sad", "angry"]
    # rows with an identity keep it; a row without one takes the block's identities cycled
    # over the session's draw of the rows (so over participants it meets every identity)
    assert list(resp["identity"])[::2] == ["male-dark", "female-light"]
    assert resp["g_jawOpen"].isna().all()  # file faces have weights, not genes
    cells = pd.read_csv(csv)  # the file's own cells are the shown shape weights
    for col in ("jawOpen", "mouthSmile_L", "mouthSmile_R"):
        np.testing.assert_array_equal(resp[f"w_{col}"].to_numpy(float), cells[col].to_numpy(float))
    for k in range(2, 10):
        token, state = svc.create_session(f"F-{k}")
        run_to_end(state, service_caller(svc, token))
    resp = export_tables(store)["categorise_responses"]
    blank = resp[resp["source_row"] == 1]
    assert len(blank) == 9 and set(blank["identity"]) == {"generic", "male-dark", "female-light"}
    store.dispose()


def test_block_errors_name_the_key(ict_model: Any, tmp_path: Path) -> None:
    def service(blocks: list[dict[str, Any]], **extra: Any) -> StudyService:
        cfg = study_from_dict({"name": "bad", "emotions": LABELS, "blocks": blocks, **extra})
        return study_service(cfg, Store(f"sqlite:///{tmp_path / 'bad.sqlite'}"), ict_model)

    with pytest.raises(
        ConfigError, match=r"blocks\[1\]: own = true, but no block that makes faces \(evolve\)"
    ):
        service([{"task": "categorise", "own": True}])
    with pytest.raises(ConfigError, match=r"blocks\[2\].labels: \['fearfull'\] not among"):
        service(
            [
                {"task": "evolve"},
                {"task": "categorise", "random": 2, "labels": ["happy", "fearfull"]},
            ]
        )
    with pytest.raises(ConfigError, match="a categorise block needs faces"):
        service([{"task": "categorise"}])
    empty = tmp_path / "empty.csv"
    empty.write_text("label,jawOpen\n")
    with pytest.raises(DataError, match=r"blocks\[1\].file .*empty.csv has no rows"):
        service([{"task": "categorise", "file": str(empty)}])
    stranger = tmp_path / "stranger.csv"
    stranger.write_text("identity,jawOpen\nsomebody,0.3\n")
    with pytest.raises(ConfigError, match=r"row 1: identity 'somebody' is not one of"):
        service([{"task": "categorise", "file": str(stranger)}])
    with pytest.raises(ConfigError, match="does not exist"):
        service([{"task": "categorise", "file": str(tmp_path / "missing.csv")}])


def test_answers_of_a_categorise_body_fit_the_view(mixed: StudyService) -> None:
    token, state = at_categorise(mixed, "C-body")
    body = categorise_body(state)
    assert body["label"] in state["view"]["labels"] and body["intensity"] == 4
    labels_before = json.dumps(state["view"]["labels"])
    again = mixed.state(token)  # the state read again shows the same face and order
    assert json.dumps(again["view"]["labels"]) == labels_before
    assert again["view"]["face"] == state["view"]["face"]


def test_replay_checks_every_categorised_face_and_catches_a_changed_one(
    mixed: StudyService, ict_model: Any
) -> None:
    first, state = mixed.create_session("R-first")
    run_to_end(state, service_caller(mixed, first))
    token, state = mixed.create_session("R-second")
    run_to_end(state, service_caller(mixed, token))
    rig, mhash = ict_model.rig, ict_model.model_hash
    ids = {
        row.participant_id: int(row.session_id)
        for row in export_tables(mixed.store)["sessions"].itertuples()
    }
    report = replay_session(mixed.store, ids["R-second"], rig, mhash, model=ict_model)
    assert report.ok and report.stimuli == 8 and report.populations == 6, report.mismatches
    with (
        mixed.store.write() as db
    ):  # a random face's weight moved by 1e-6; an own face's label order
        stims = {
            s.source: s
            for s in db.scalars(
                select(StimulusRow).join(TrialRow).where(TrialRow.session_id == ids["R-second"])
            )
        }
        w = json.loads(stims["random"].weights)
        w[3] += 1e-6
        stims["random"].weights = json.dumps(w)
        stims["own"].labels = json.dumps(list(reversed(json.loads(stims["own"].labels))))
        g = json.loads(stims["other"].genes)
        g[0] = 1.0 - g[0]
        stims["other"].genes = json.dumps(g)
    report = replay_session(mixed.store, ids["R-second"], rig, mhash, model=ict_model)
    text = " / ".join(report.mismatches)
    assert len(report.mismatches) == 3, text
    assert "(random face): weights differ by up to 1e-06" in text
    assert "(own face): labels offered" in text
    assert "(other face): genes differ from its source face" in text
