"""The study's side of the task protocol: what a task is given (:class:`TaskEnv`) and what the
study answers its questions with — the faces participants made, by every registered task that
makes faces, and the study's completed sessions."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from sqlalchemy import Select, select
from sqlalchemy.orm import Session

from emogen.study.context import StudyContext
from emogen.study.tables import SessionRow
from emogen.study.weights import StudyCorrectors
from emogen.tasks.protocol import MadeFace, TaskEnv
from emogen.tasks.registry import TASKS, task_named


def made_faces(db: Session, where: Sequence[Any]) -> list[MadeFace]:
    """The faces participants made in the finished trials matching ``where``, by every task."""
    return [face for task in TASKS.values() for face in task.made_faces(db, where)]


def prepare(ctx: StudyContext) -> dict[int, Any]:
    """What each block's task reads once when the service starts (checked before anyone
    starts), by block index."""
    return {
        k: task_named(b.task).prepare(ctx, k, b) for k, b in enumerate(ctx.config.study_blocks())
    }


def rows_of(ctx: StudyContext, prepared: dict[int, Any]) -> dict[int, int]:
    """The rows of each block's face table, where it reads one."""
    out: dict[int, int] = {}
    for k, b in enumerate(ctx.config.study_blocks()):
        n = task_named(b.task).rows(prepared[k])
        if n is not None:
            out[k] = n
    return out


def task_env(ctx: StudyContext, correctors: StudyCorrectors, prepared: dict[int, Any]) -> TaskEnv:
    """What the study's tasks are given."""

    def sessions_done(session_id: int) -> Select[Any]:
        return select(SessionRow.id).where(
            SessionRow.study_id.in_(ctx.accepted),
            SessionRow.stage == "done",
            SessionRow.id != session_id,
        )

    return TaskEnv(
        ctx=ctx,
        correctors=correctors,
        prepared=prepared,
        made_faces=made_faces,
        sessions_done=sessions_done,
    )
