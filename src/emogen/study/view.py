"""The participant's view of a session: the state the browser shows, as typed JSON.

These TypedDicts are the browser contract: the web layer answers with them and its OpenAPI
schema (and the JS types generated from it) are derived from them, with ``view`` the union of
the registered tasks' views keyed by ``task`` (:meth:`emogen.tasks.protocol.Task.view`: only
what the participant may know). A step that has just shown something passes it on
(:class:`~emogen.tasks.protocol.Outcome`) so the task's view need not read it back.
"""

from __future__ import annotations

from typing import Any, Literal, NotRequired
from urllib.parse import quote

from sqlalchemy import bindparam, select
from sqlalchemy.orm import Session
from typing_extensions import TypedDict

from emogen.study.config import StudyConfig
from emogen.study.queries import n_trials, trial_at
from emogen.study.tables import SessionRow, TrialRow
from emogen.tasks.protocol import FaceView, Outcome, TaskEnv
from emogen.tasks.registry import task_named

__all__ = ["FaceView", "SessionState", "completion", "session_state"]

Stage = Literal["instructions", "trial", "done"]
TrialStatus = Literal["pending", "active", "rating", "done"]


class Progress(TypedDict):
    """Trial and block shown (0-based) of how many."""

    trial: int
    trials: int
    block: int
    blocks: int


class TrialView(TypedDict):
    """The current trial: its task and block, its instruction line, its identity (the face
    shown), its attempt (restarts) and status; ``next_identity``: the identity of the session's
    next trial, so that the page can make that face model ready while the participant is on
    this trial (None at the last trial, and before a block that chooses its faces when it
    starts)."""

    position: int
    block: int
    task: str
    prompt: str
    identity: str
    next_identity: str | None
    attempt: int
    status: TrialStatus


class Completion(TypedDict):
    """What a participant sees at the end: a message, a code, a link back."""

    message: str
    code: str | None
    redirect_url: str | None


class SessionState(TypedDict):
    """The participant's view of the session (``view``: the current trial's, by its task)."""

    stage: Stage
    participant_id: str
    progress: Progress
    trial: TrialView | None
    view: dict[str, Any] | None
    completion: Completion | None
    #: true when the request's step key was already done (nothing was changed)
    replayed: NotRequired[bool]


def completion(config: StudyConfig, participant_id: str) -> Completion:
    """The end of the study, with the participant's code and redirect link filled in."""
    c = config.completion
    url = None
    if c.redirect_url:
        code, pid = quote(c.code or "", safe=""), quote(participant_id, safe="")
        url = c.redirect_url
        for name in ("code", "completion_code"):
            url = url.replace("{" + name + "}", code)
        for name in ("participant", "participant_id", config.participant_param):
            url = url.replace("{" + name + "}", pid)
    return {"message": c.message, "code": c.code, "redirect_url": url}


#: The identity of a session's trial at a position ('' for a trial of a block that draws its
#: faces when it starts, before it has).
_NEXT_IDENTITY = select(TrialRow.identity).where(
    TrialRow.session_id == bindparam("session_id"), TrialRow.position == bindparam("position")
)


def _current_trial(db: Session, sess: SessionRow, shown: Outcome | None) -> TrialRow | None:
    """The session's current trial: the one a step has just shown (no query), or the one read."""
    row = getattr(shown.shown, "trial", None) if shown is not None else None
    if isinstance(row, TrialRow) and (row.session_id, row.position) == (
        sess.id,
        sess.current_trial,
    ):
        return row
    return trial_at(db, sess.id, sess.current_trial)


def session_state(
    db: Session, env: TaskEnv, sess: SessionRow, shown: Outcome | None = None
) -> SessionState:
    """The session as the participant sees it now (``shown``: what a step has just stored to
    show, handed to the task's view)."""
    config: StudyConfig = env.config
    trials = n_trials(sess)
    blocks = len(config.study_blocks())
    stage: Stage = (
        "done" if sess.stage == "done" else "trial" if sess.stage == "trial" else "instructions"
    )
    state: SessionState = {
        "stage": stage,
        "participant_id": sess.participant_id,
        "progress": {"trial": sess.current_trial, "trials": trials, "block": 0, "blocks": blocks},
        "trial": None,
        "view": None,
        "completion": None,
    }
    if stage == "done":
        state["completion"] = completion(config, sess.participant_id)
        state["progress"]["trial"] = trials - 1
        state["progress"]["block"] = blocks - 1
        return state
    row = _current_trial(db, sess, shown) if stage == "trial" else None
    if row is None:
        return state
    task = task_named(row.task)
    status: TrialStatus = row.status  # type: ignore[assignment]  # a stored TrialStatus
    state["progress"]["block"] = row.block
    state["trial"] = {
        "position": row.position,
        "block": row.block,
        "task": row.task,
        "prompt": task.prompt(env, row),
        "identity": row.identity,
        "next_identity": db.scalar(
            _NEXT_IDENTITY, {"session_id": sess.id, "position": row.position + 1}
        )
        or None,
        "attempt": row.attempt,
        "status": status,
    }
    state["view"] = task.view(env, db, row, None if shown is None else shown.shown)
    return state
