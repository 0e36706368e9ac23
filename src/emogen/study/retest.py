"""Retest sessions: a study that is the retest of another (``retest_of = "NAME"``), taken on
another day by the same participants.

A retest session is made only for a participant id with a completed session of the study
``NAME`` (any version of it) in the same database; anyone else is refused (409), naming the
study — an anonymous id never matches. The link is the participant id and the study name: the
export's ``sessions`` table gives each retest session's ``retest_of_session_id`` (the first
session's id), and ``emogen study retest-reliability FIRST RETEST`` compares the faces of the
two sessions (:mod:`emogen.analysis.retest`).
"""

from __future__ import annotations

import json

from sqlalchemy import select
from sqlalchemy.orm import Session

from emogen.study.errors import StepConflict
from emogen.study.tables import SessionRow, StudyRow


def first_session(db: Session, name: str, participant_id: str) -> SessionRow | None:
    """The participant's session of the study ``name`` (any version), if any."""
    return db.scalar(
        select(SessionRow)
        .join(StudyRow, SessionRow.study_id == StudyRow.id)
        .where(StudyRow.name == name, SessionRow.participant_id == participant_id)
        .order_by(SessionRow.id)
        .limit(1)
    )


def check_retest(db: Session, retest_of: str | None, participant_id: str) -> None:
    """Refuse a retest session to a participant without a completed first session."""
    if retest_of is None:
        return
    first = first_session(db, retest_of, participant_id)
    if first is None or first.completed_at is None:
        had = "has not completed" if first is not None else "has no session of"
        raise StepConflict(
            f"participant '{participant_id}' {had} the study '{retest_of}': this study is its "
            "retest, for the participants who completed it (check the link's participant id, "
            "or ask the researcher)"
        )


def retest_links(
    db: Session, studies: dict[int, StudyRow], sessions: list[SessionRow]
) -> dict[int, int]:
    """Each retest session's first session id, by the retest session's id."""
    out: dict[int, int] = {}
    for s in sessions:
        name = json.loads(studies[s.study_id].config_json).get("retest_of")
        if name:
            first = first_session(db, str(name), s.participant_id)
            if first is not None:
                out[s.id] = first.id
    return out
