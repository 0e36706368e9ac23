"""The plain statements a study step writes with (no ORM unit of work: a step's rows are
written once and not read back in it), built once with bound parameters."""

from __future__ import annotations

from datetime import datetime
from typing import Any

from sqlalchemy import Connection, Update, bindparam, insert, update

from emogen.study.queries import Executor, TrialRecord
from emogen.study.tables import (
    RestartRow,
    SelectionRow,
    SessionRow,
    StepRow,
    TrialRow,
    core_table,
    utcnow,
)

#: Plain inserts of the rows a step writes.
_INSERT_STEP = insert(core_table(StepRow))
INSERT_SELECTION = insert(core_table(SelectionRow))
INSERT_RESTART = insert(core_table(RestartRow))
_SESSIONS = core_table(SessionRow)
_TOUCH_SESSION = (
    update(_SESSIONS).where(_SESSIONS.c.id == bindparam("sid")).values(updated_at=bindparam("at"))
)


_TRIALS = core_table(TrialRow)
_ADVANCE_TRIAL: dict[tuple[str, ...], Update] = {
    names: update(_TRIALS)
    .where(_TRIALS.c.id == bindparam("trial_id"))
    .values({name: bindparam(f"new_{name}") for name in names})
    for names in (
        ("generation", "engine_state"),
        ("status", "final_face_id", "generation", "engine_state"),
        ("attempt", "generation", "engine_state"),
    )
}


def advance_trial(conn: Connection, row: TrialRecord, **values: Any) -> TrialRecord:
    """UPDATE the trial's columns by a prepared statement; the trial as it is now."""
    params = {f"new_{name}": value for name, value in values.items()}
    conn.execute(_ADVANCE_TRIAL[tuple(values)], {"trial_id": row.id, **params})
    return row._replace(**values)


def record_step(ex: Executor, session_id: int, kind: str, key: str, digest: str) -> datetime:
    """Record the step under its key and touch the session; returns the time."""
    now = utcnow()
    ex.execute(
        _INSERT_STEP,
        {"session_id": session_id, "key": key, "kind": kind, "request_hash": digest,
         "created_at": now},
    )  # fmt: skip
    ex.execute(_TOUCH_SESSION, {"sid": session_id, "at": now})
    return now
