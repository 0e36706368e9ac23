"""Reads of the study database the steps and the view need; each takes an open session."""

from __future__ import annotations

import json
from typing import NamedTuple

from sqlalchemy import bindparam, func, select
from sqlalchemy.orm import Session

from emogen.study.errors import SessionNotFound, StepConflict
from emogen.study.tables import SessionRow, StepRow, StudyRow, TrialRow

_BY_TOKEN = select(SessionRow).where(SessionRow.token == bindparam("token"))
_BY_TOKEN_LOCKED = _BY_TOKEN.with_for_update()
_TRIAL_AT = select(TrialRow).where(
    TrialRow.session_id == bindparam("session_id"), TrialRow.position == bindparam("position")
)
_STEP_WITH_KEY = select(StepRow.kind, StepRow.request_hash).where(
    StepRow.session_id == bindparam("session_id"), StepRow.key == bindparam("key")
)


NO_SESSION = "no session with this link; check the address"
ENDED_SESSION = (
    "this session was ended when the researcher changed the study's design; thank you for "
    "your time — please contact the researcher"
)


def _of_study(sess: SessionRow | None, study_ids: tuple[int, ...]) -> SessionRow:
    """The session found by its token, if it is one of this study's (or its design's)."""
    if sess is None:
        raise SessionNotFound(NO_SESSION)
    if sess.stage == "ended":
        raise StepConflict(ENDED_SESSION)
    if sess.study_id not in study_ids:
        raise StepConflict(
            "this session belongs to another version of the study config than the one the "
            "server runs now; ask the researcher"
        )
    return sess


def session_by_token(
    db: Session, token: str, study_ids: tuple[int, ...], *, lock: bool = False
) -> SessionRow:
    """The session of this token in these study rows (locked for update if asked)."""
    found = db.scalar(_BY_TOKEN_LOCKED if lock else _BY_TOKEN, {"token": token})
    return _of_study(found, study_ids)


def lock_study(db: Session, study_id: int) -> None:
    """Lock the study's row until the transaction ends (PostgreSQL; SQLite writes are serial)."""
    db.get(StudyRow, study_id, with_for_update=True)


def session_of_participant(
    db: Session, study_ids: tuple[int, ...], participant_id: str
) -> SessionRow | None:
    """The participant's session in any of these study rows (the newest, if several)."""
    return db.scalar(
        select(SessionRow)
        .where(SessionRow.study_id.in_(study_ids), SessionRow.participant_id == participant_id)
        .order_by(SessionRow.id.desc())
        .limit(1)
    )


def session_of_create_key(
    db: Session, study_ids: tuple[int, ...], key_hash: str
) -> SessionRow | None:
    """The session made with this creation key (its SHA-256) in these study rows."""
    return db.scalar(
        select(SessionRow)
        .where(SessionRow.study_id.in_(study_ids), SessionRow.create_key == key_hash)
        .limit(1)
    )


def count_sessions(db: Session, study_ids: tuple[int, ...]) -> int:
    n = db.scalar(
        select(func.count()).select_from(SessionRow).where(SessionRow.study_id.in_(study_ids))
    )
    return int(n or 0)


def sessions_by_source(db: Session, study_ids: tuple[int, ...]) -> dict[str, int]:
    """How many sessions of these study rows had their id from the link (``url``), generated
    (``generated``) or simulated."""
    rows = db.execute(
        select(SessionRow.participant_source, func.count())
        .where(SessionRow.study_id.in_(study_ids))
        .group_by(SessionRow.participant_source)
    )
    return {str(source): int(n) for source, n in rows}


def n_trials(sess: SessionRow) -> int:
    """How many trials the session has (its stored trial order)."""
    return len(json.loads(sess.trial_order))


def trial_at(db: Session, session_id: int, position: int) -> TrialRow | None:
    return db.scalar(_TRIAL_AT, {"session_id": session_id, "position": position})


class StepTaken(NamedTuple):
    """A step already taken: its kind and the hash of its request (idempotency)."""

    kind: str
    request_hash: str


def step_with_key(db: Session, session_id: int, key: str) -> StepTaken | None:
    """The session's step with this key, if it was taken (a plain row, no ORM object: every
    step asks)."""
    found = db.execute(_STEP_WITH_KEY, {"session_id": session_id, "key": key}).first()
    return None if found is None else StepTaken(found[0], found[1])


def current_trial(db: Session, sess: SessionRow) -> TrialRow | None:
    """The session's current trial (None before or after its trials)."""
    if sess.stage != "trial":
        return None
    return trial_at(db, sess.id, sess.current_trial)
