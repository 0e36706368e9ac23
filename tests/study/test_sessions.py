"""Sessions on SQLite and PostgreSQL: flow, durability before answering, idempotency, conflicts."""

from __future__ import annotations

import json
import threading

import pytest
from sqlalchemy import func, select

from emogen.correct import correct_faces, model_correctives
from emogen.errors import ConfigError, SelectionError
from emogen.ga.engine import Engine, correctives_of
from emogen.study.errors import SessionNotFound, StepConflict
from emogen.study.sessions import StudyService, full_weights
from emogen.study.storage import Store
from emogen.study.tables import StepRow, TrialRow
from emogen.tasks.evolve.tables import FaceRow, PopulationRow, SelectionRow
from tests.study.drive import (
    choose,
    do,
    new_key,
    run_to_end,
    service_caller,
    step_args,
    study_service,
)


def count(store: Store, table: type) -> int:
    with store.read() as db:
        return int(db.scalar(select(func.count()).select_from(table)) or 0)


def test_whole_session_stores_every_generation_and_selection(service: StudyService) -> None:
    token, state = service.create_session("P-001")
    assert state["stage"] == "instructions" and state["progress"]["trials"] == 2
    state = do(service, "begin", token, new_key())
    assert state["stage"] == "trial" and len(state["view"]["population"]["faces"]) == 10
    n_columns = len(service.ctx.weight_names)
    assert n_columns > 57  # the shapes, then the correctives (correct = true)
    assert len(state["view"]["population"]["faces"][0]["weights"]) == n_columns
    final = run_to_end(state, service_caller(service, token))
    assert final["stage"] == "done"
    assert final["completion"]["code"] == "DONE-42"
    assert final["completion"]["redirect_url"] == "https://example.org/done?cc=DONE-42"
    # 2 trials × (G + 1 = 3) generations, 10 faces each; one selection per generation
    assert count(service.store, PopulationRow) == 6
    assert count(service.store, FaceRow) == 60
    assert count(service.store, SelectionRow) == 6
    with service.store.read() as db:
        trials = db.scalars(select(TrialRow).order_by(TrialRow.position)).all()
        assert [t.status for t in trials] == ["done", "done"]
        assert {t.emotion for t in trials} == {"happy", "sad"}
        assert all(t.final_face_id is not None for t in trials)


def test_state_is_committed_before_answering_and_survives_a_new_server(
    service: StudyService, small_study, ict_model
) -> None:
    token, _ = service.create_session("P-002")
    state = do(service, "begin", token, new_key())
    elite, others = choose(state)
    state = do(service, "select", token, new_key(), **step_args(state), elite=elite, others=others)
    # a fresh service on the same database (a restarted server) sees exactly the same state
    other = StudyService(
        small_study,
        Store(service.store.url),
        ict_model.rig,
        model_name=ict_model.name,
        model_hash=ict_model.model_hash,
        model=ict_model,
    )
    assert other.state(token) == state
    assert other.ctx.study_id == service.ctx.study_id
    # and the stored engine state regenerates the shown population exactly
    with other.store.read() as db:
        row = db.scalar(select(TrialRow).where(TrialRow.position == 0))
        engine = Engine.from_json(
            row.engine_state, ict_model.rig, corrector=correctives_of(ict_model)
        )
    shown = [f["weights"] for f in state["view"]["population"]["faces"]]
    assert full_weights(engine.ask()).tolist() == shown
    other.store.dispose()


def test_repeated_key_is_one_step_and_stale_request_conflicts(service: StudyService) -> None:
    token, _ = service.create_session("P-003")
    state = do(service, "begin", token, new_key())
    elite, others = choose(state)
    key = new_key()
    args = dict(**step_args(state), elite=elite, others=others)
    after = do(service, "select", token, key, **args)
    again = do(service, "select", token, key, **args)  # a double click / retried request
    assert again.pop("replayed") is True
    assert again == after
    assert count(service.store, SelectionRow) == 1
    assert count(service.store, PopulationRow) == 2
    # the same generation again with a new key: the page was stale
    with pytest.raises(StepConflict, match=r"generation 0 .* generation 1"):
        do(service, "select", token, new_key(), **args)
    # the same key for a different request
    with pytest.raises(StepConflict, match="already used"):
        do(service, "select", token, key, **{**args, "generation": 1})
    assert count(service.store, SelectionRow) == 1


def test_concurrent_double_submissions_make_one_generation(service: StudyService) -> None:
    token, _ = service.create_session("P-004")
    state = do(service, "begin", token, new_key())
    elite, others = choose(state)
    args = dict(**step_args(state), elite=elite, others=others)
    results: list[object] = []

    def submit(key: str) -> None:
        try:
            results.append(do(service, "select", token, key, **args)["view"]["generation"])
        except StepConflict as exc:
            results.append(exc)

    threads = [threading.Thread(target=submit, args=(f"double-{i:04d}",)) for i in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert results.count(1) == 1
    assert sum(isinstance(r, StepConflict) for r in results) == 7
    assert count(service.store, SelectionRow) == 1
    assert count(service.store, PopulationRow) == 2


def test_invalid_selections_leave_no_trace(service: StudyService) -> None:
    token, _ = service.create_session("P-005")
    state = do(service, "begin", token, new_key())
    ids = [f["id"] for f in state["view"]["population"]["faces"]]
    where = step_args(state)
    with pytest.raises(SelectionError, match="not in the population"):
        do(service, "select", token, new_key(), **where, elite=999, others=[])
    with pytest.raises(SelectionError, match=r"number of selections must be in \[1, 4\]"):
        do(service, "select", token, new_key(), **where, elite=ids[0], others=ids[1:6])
    with pytest.raises(SelectionError, match="must not also be"):
        do(service, "select", token, new_key(), **where, elite=ids[0], others=[ids[0]])
    with pytest.raises(StepConflict, match="trial 2"):
        do(service, "select", token, new_key(), **{**where, "trial": 1}, elite=ids[0], others=[])
    with pytest.raises(StepConflict, match="not waiting for a rating"):
        do(service, "rate", token, new_key(), trial=0, value=3)
    assert count(service.store, SelectionRow) == 0
    assert count(service.store, StepRow) == 1  # the begin
    assert service.state(token) == {**state}


def test_restart_makes_a_new_attempt(service: StudyService) -> None:
    token, _ = service.create_session("P-006")
    state = do(service, "begin", token, new_key())
    elite, others = choose(state)
    state = do(service, "select", token, new_key(), **step_args(state), elite=elite, others=others)
    state = do(service, "restart", token, new_key(), **step_args(state), response_ms=10.0)
    assert state["trial"]["attempt"] == 1 and state["view"]["generation"] == 0
    final = run_to_end(state, service_caller(service, token))
    assert final["stage"] == "done"
    with service.store.read() as db:
        attempts = db.scalars(
            select(PopulationRow.attempt).join(TrialRow).where(TrialRow.position == 0)
        ).all()
    assert sorted(attempts) == [0, 0, 1, 1, 1]


def test_rating_range_and_cross_session_tokens(service: StudyService) -> None:
    token_a, _ = service.create_session("P-007")
    token_b, _ = service.create_session("P-008")
    state = do(service, "begin", token_a, new_key())
    state = run_to_end(
        state, service_caller(service, token_a), stop=lambda s: s["trial"]["status"] == "rating"
    )
    assert state["view"]["rating"]["points"] == 7 and len(
        state["view"]["rating"]["face"]["weights"]
    ) == len(service.ctx.weight_names)
    with pytest.raises(SelectionError, match=r"rating must be an integer in \[1, 7\]"):
        do(service, "rate", token_a, new_key(), trial=0, value=8)
    # B is still at the instructions: A's step with B's token does not touch A
    with pytest.raises(StepConflict, match="not in a trial"):
        do(service, "rate", token_b, new_key(), trial=0, value=3)
    with pytest.raises(SessionNotFound):
        service.state("x" * 32)
    assert service.state(token_b)["stage"] == "instructions"


def test_participant_ids_resume_only_with_their_token(service: StudyService) -> None:
    token, _ = service.create_session("PROLIFIC-abc")
    with pytest.raises(StepConflict, match="already has a session"):
        service.create_session("PROLIFIC-abc")
    with pytest.raises(StepConflict, match="already has a session"):
        service.create_session("PROLIFIC-abc", resume_token="y" * 32)
    again, state = service.create_session("PROLIFIC-abc", resume_token=token)
    assert again == token and state["participant_id"] == "PROLIFIC-abc"
    anon, state = service.create_session(None)
    assert state["participant_id"].startswith("anon-") and anon != token
    with pytest.raises(ConfigError, match="participant id"):
        service.create_session("bad id with spaces")


def test_resume_by_participant_id_continues_the_session_from_any_browser(
    db_url: str, small_study, ict_model
) -> None:
    """``resume = "participant_id"`` (#40, embedded studies): a reopened link — no token, a new
    creation key — continues the same session where it stood; a generated (anonymous) id never
    resumes anyone's session (the default, ``link``, refuses: the test above)."""
    store = Store(db_url)
    svc = study_service(
        small_study.model_copy(update={"resume": "participant_id"}), store, ict_model
    )
    token, _ = svc.create_session("PROLIFIC-re", create_key="tab-1")
    state = do(svc, "begin", token, new_key())
    elite, others = choose(state)
    moved = do(svc, "select", token, new_key(), **step_args(state), elite=elite, others=others)
    again, resumed = svc.create_session("PROLIFIC-re", create_key="tab-2")  # a new tab
    assert again == token
    assert resumed["progress"] == moved["progress"]
    assert resumed["view"]["population"] == moved["view"]["population"]
    anon, _ = svc.create_session(None, create_key="tab-3")
    assert anon != token
    assert svc.create_session("PROLIFIC-other")[0] not in (token, anon)
    store.dispose()


def test_sessions_get_recorded_seeds_and_orders(service: StudyService) -> None:
    from emogen.study.design import participant_seed
    from emogen.study.tables import SessionRow

    for i in range(3):
        service.create_session(f"S-{i}")
    with service.store.read() as db:
        rows = db.scalars(select(SessionRow).order_by(SessionRow.number)).all()
        seeds = [r.seed for r in rows]
        orders = [json.loads(r.trial_order) for r in rows]
    # study seed 1234: a participant's seed is a keyed hash of it and the participant id
    assert seeds == [participant_seed(1234, f"S-{i}") for i in range(3)]
    assert len(set(seeds)) == 3
    assert all(sorted(o) == [0, 1] for o in orders)


def test_corrective_columns_are_stored_after_the_shapes(ict_model) -> None:
    from dataclasses import dataclass

    import numpy as np

    from emogen.config import GAConfig
    from emogen.study.sessions import full_weights, weight_names

    pop = Engine(GAConfig(), ict_model.rig, 3).ask()
    assert full_weights(pop).shape == (10, 57) and len(weight_names(pop, ict_model.rig)) == 57

    @dataclass
    class Correction:
        combinational_names: tuple[str, ...]
        collision_names: tuple[str, ...]
        combinational: np.ndarray
        collision: np.ndarray

    class Corrected:
        def __init__(self) -> None:
            self.weights = pop.weights
            self.correction = Correction(("c1",), ("k1", "k2"), np.ones((10, 1)), np.zeros((10, 2)))

        def __len__(self) -> int:
            return 10

    corrected = Corrected()
    names = weight_names(corrected, ict_model.rig)  # type: ignore[arg-type]
    assert names[-3:] == ["c1", "k1", "k2"]
    w = full_weights(corrected)  # type: ignore[arg-type]
    assert w.shape == (10, 60) and (w[:, 57] == 1).all() and (w[:, :57] == pop.weights).all()


def test_correct_setting_decides_the_corrective_columns(db_url: str, ict_model) -> None:  # type: ignore[no-untyped-def]
    import numpy as np

    from emogen.study.config import study_from_dict
    from emogen.study.storage import Store
    from tests.study.conftest import SMALL_STUDY

    store = Store(db_url)
    corrected = study_from_dict(SMALL_STUDY)
    assert corrected.correct  # the default
    with pytest.raises(ConfigError, match="correct = true"):
        StudyService(
            corrected,
            store,
            ict_model.rig,
            model_name=ict_model.name,
            model_hash=ict_model.model_hash,
        )
    svc = StudyService(
        corrected,
        store,
        ict_model.rig,
        model_name=ict_model.name,
        model_hash=ict_model.model_hash,
        model=ict_model,
    )
    assert svc.ctx.weight_names == (*ict_model.shape_names, *model_correctives(ict_model).names)
    token, _ = svc.create_session("P-C1")
    shown = np.array(
        [f["weights"] for f in do(svc, "begin", token, new_key())["view"]["population"]["faces"]]
    )
    result = correct_faces(ict_model, shown[:, : ict_model.n_shapes])
    np.testing.assert_array_equal(shown[:, ict_model.n_shapes :], result.correctives)
    plain = study_from_dict({**SMALL_STUDY, "name": "plain", "correct": False})
    svc = StudyService(
        plain, store, ict_model.rig, model_name=ict_model.name, model_hash=ict_model.model_hash
    )
    assert svc.ctx.weight_names == ict_model.shape_names
    token, _ = svc.create_session("P-C2")
    faces = do(svc, "begin", token, new_key())["view"]["population"]["faces"]
    assert all(len(f["weights"]) == ict_model.n_shapes for f in faces)
    store.dispose()
