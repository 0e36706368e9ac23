"""A selection's or restart's first read (:func:`step_read`, one statement) finds what reading
the session, the key's step, the trial and its population one by one finds, in every stage of
a session, on both databases."""

from __future__ import annotations

import threading
from typing import Any

import pytest
from sqlalchemy import event, select

from emogen.study.errors import SessionNotFound, StepConflict
from emogen.study.queries import StepRead, population_at, step_read, trial_at
from emogen.study.sessions import StudyService
from emogen.study.tables import SessionRow, StepRow
from tests.study.drive import choose, new_key, step_args


def reference(service: StudyService, token: str, key: str) -> dict[str, Any]:
    """The same facts by separate ORM reads."""
    with service.store.read() as db:
        sess = db.scalars(select(SessionRow).where(SessionRow.token == token)).one()
        step = db.scalars(
            select(StepRow).where(StepRow.session_id == sess.id, StepRow.key == key)
        ).first()
        trial = trial_at(db, sess.id, sess.current_trial)
        pop = (
            None if trial is None else population_at(db, trial.id, trial.attempt, trial.generation)
        )
        return {
            "session": (sess.id, sess.stage, sess.current_trial, sess.participant_id),
            "taken": None if step is None else (step.kind, step.request_hash),
            "trial": None
            if trial is None
            else (trial.id, trial.status, trial.attempt, trial.generation, trial.engine_state),
            "shown": None if pop is None else (pop.id, pop.shown_at),
        }


def found(service: StudyService, token: str, key: str) -> dict[str, Any]:
    with service.store.write() as db:
        read: StepRead = step_read(db.connection(), token, service.ctx.study_id, key)
    s, t, p = read.session, read.trial, read.shown
    return {
        "session": (s.id, s.stage, s.current_trial, s.participant_id),
        "taken": None if read.taken is None else tuple(read.taken),
        "trial": None if t is None else (t.id, t.status, t.attempt, t.generation, t.engine_state),
        "shown": None if p is None else (p.id, p.shown_at),
    }


def test_step_read_finds_what_separate_reads_find(service: StudyService) -> None:
    token, _ = service.create_session("READ-1")
    used = new_key()
    seen = [found(service, token, used)]  # instructions: no population shown yet
    assert seen[0] == reference(service, token, used)
    assert seen[0]["shown"] is None and seen[0]["taken"] is None
    state = service.begin(token, used)
    while state["stage"] != "done":
        for key in (used, new_key()):  # a key taken (the begin's) and a fresh one
            seen.append(found(service, token, key))
            assert seen[-1] == reference(service, token, key)
        if state["trial"]["status"] == "active":
            elite, others = choose(state)
            state = service.select(token, new_key(), **step_args(state), elite=elite, others=others)
        else:
            state = service.rate(token, new_key(), trial=state["progress"]["trial"], value=3)
    seen.append(found(service, token, used))
    assert seen[-1] == reference(service, token, used)
    stages = {(s["session"][1], s["trial"] and s["trial"][1]) for s in seen}
    assert {
        ("instructions", "pending"),
        ("trial", "active"),
        ("trial", "rating"),
        ("done", "done"),
    } <= stages
    # every read under the begin's key finds that step (the same one); under fresh keys, none
    begin_step = seen[1]["taken"]
    assert begin_step is not None and begin_step[0] == "begin"
    assert all(s["taken"] == begin_step for s in seen[1::2])
    assert all(s["taken"] is None for s in seen[2::2])
    assert any(s["shown"] is not None and s["trial"][3] > 0 for s in seen)  # a later generation


def test_step_read_refuses_unknown_tokens_and_other_studies(service: StudyService) -> None:
    token, _ = service.create_session("READ-2")
    with service.store.write() as db, pytest.raises(SessionNotFound, match="no session"):
        step_read(db.connection(), "no-such-token", service.ctx.study_id, new_key())
    with service.store.write() as db, pytest.raises(StepConflict, match="another version"):
        step_read(db.connection(), token, service.ctx.study_id + 1, new_key())


def test_a_selection_reads_once_in_its_write_transaction(service: StudyService) -> None:
    """The write transaction of a selection reads by one SELECT (PostgreSQL: after the one
    locking the session's row), then writes (the reads it replaced cost a statement each, and
    on PostgreSQL a round trip each)."""
    token, _ = service.create_session("READ-3")
    state = service.begin(token, new_key())
    elite, others = choose(state)
    main = threading.get_ident()
    statements: list[str] = []

    def seen(conn: Any, cursor: Any, statement: str, *args: Any) -> None:
        if threading.get_ident() != main or not service.store.is_sqlite:  # the writer's
            statements.append(statement.split()[0].upper())

    event.listen(service.store.engine, "before_cursor_execute", seen)
    try:
        service.select(token, new_key(), **step_args(state), elite=elite, others=others)
    finally:
        event.remove(service.store.engine, "before_cursor_execute", seen)
    # SQLite: the writer thread's statements; PostgreSQL: all (no read before the transaction:
    # this process stored the state the selection's GA work starts from)
    writes = [s for s in statements if s != "BEGIN"]
    reads = 1 if service.store.is_sqlite else 2
    assert writes[:reads] == ["SELECT"] * reads and writes.count("SELECT") == reads, statements
    assert {"INSERT", "UPDATE"} <= set(writes)
