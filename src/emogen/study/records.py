"""What a page embedding the study (the jsPsych plugin) reads besides the session's state: the
study's blocks, and a trial's record as the server keeps it — the researcher's session id, the
seeds, the trial's result as its task gives it (:meth:`emogen.tasks.protocol.Task.result`: only
what the participant may know) — so the embedding experiment's own data carry them too.

Seeds go out as decimal strings: they are 64-bit integers, past what a JavaScript number holds
exactly.
"""

from __future__ import annotations

from typing import Any, Literal

from sqlalchemy.orm import Session
from typing_extensions import TypedDict

from emogen.study.context import StudyContext
from emogen.study.errors import SessionNotFound
from emogen.study.queries import trial_at
from emogen.study.tables import SessionRow
from emogen.tasks.protocol import TaskEnv
from emogen.tasks.registry import task_named


class BlockInfo(TypedDict):
    """A block of the study: its position (0-based), name, task, number of trials and what its
    trials show (:meth:`emogen.tasks.protocol.Task.shows`)."""

    block: int
    name: str
    task: str
    trials: int
    shows: dict[str, Any]


class StudyInfo(TypedDict):
    """The study as an embedding page needs it: its blocks, the names of a face's weights
    (shapes, then correctives: the order of every ``weights`` list) and the framing its faces
    are shown in (``face`` or ``oval``: :mod:`emogen.study.framing`)."""

    name: str
    title: str
    participant_param: str
    framing: Literal["face", "oval"]
    blocks: list[BlockInfo]
    weight_names: list[str]


class TrialRecord(TypedDict):
    """One trial of a session as recorded: where it is, its seeds and its result (by its
    task, ``task`` first; None until the task has one)."""

    session_id: int
    participant_id: str
    study: str
    trial: int
    block: int
    block_name: str
    task: str
    status: str
    identity: str
    attempt: int
    seed: str
    session_seed: str
    result: dict[str, Any] | None


def study_info(ctx: StudyContext) -> StudyInfo:
    """The study's blocks (names as in the exports: ``block<k>`` where none is given)."""
    config = ctx.config
    counts: dict[int, int] = {}
    for c in ctx.conditions:
        counts[c.block] = counts.get(c.block, 0) + 1
    resolved = config.study_blocks()
    blocks: list[BlockInfo] = [
        {
            "block": k,
            "name": name,
            "task": resolved[k].task,
            "trials": counts.get(k, 0),
            "shows": task_named(resolved[k].task).shows(resolved[k], config),
        }
        for k, name in enumerate(block_names(ctx))
    ]
    return {
        "name": config.name,
        "title": config.title,
        "participant_param": config.participant_param,
        "framing": "oval" if config.framing == "oval" else "face",
        "blocks": blocks,
        "weight_names": list(ctx.weight_names),
    }


def block_names(ctx: StudyContext) -> list[str]:
    """Each block's name as the exports give it (``block<k>``, from 1, where none is given)."""
    return [b.name or f"block{k + 1}" for k, b in enumerate(ctx.config.study_blocks())]


def trial_record(db: Session, env: TaskEnv, sess: SessionRow, position: int) -> TrialRecord:
    """Trial ``position`` of the session as recorded (404 when the session has no such trial)."""
    row = trial_at(db, sess.id, position)
    if row is None:
        raise SessionNotFound(f"this session has no trial {position}")
    ctx: StudyContext = env.ctx
    names = block_names(ctx)
    return {
        "session_id": sess.id,
        "participant_id": sess.participant_id,
        "study": ctx.config.name,
        "trial": row.position,
        "block": row.block,
        "block_name": names[row.block] if row.block < len(names) else f"block{row.block + 1}",
        "task": row.task,
        "status": row.status,
        "identity": row.identity,
        "attempt": row.attempt,
        "seed": str(row.seed),
        "session_seed": str(sess.seed),
        "result": task_named(row.task).result(env, db, row),
    }
