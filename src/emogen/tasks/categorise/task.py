"""The ``categorise`` task: one face per trial, answered with one of the study's emotion labels
(offered in an order drawn per trial), optionally an intensity and a confidence rating.

Its block is :class:`~emogen.tasks.categorise.block.CategoriseBlock`; a block's faces are drawn
and stored for all its trials when a session reaches it (:mod:`~emogen.tasks.categorise.draw`),
each shown when its trial starts; an answer is stored before the server answers. The view
carries the face and the labels only: never the emotion the face was made for, nor whose face
it is (:func:`~emogen.tasks.categorise.view.categorise_view`).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from typing import Annotated, Any, ClassVar, Literal

import numpy as np
from pydantic import Field
from sqlalchemy import func, select
from sqlalchemy.orm import Session

from emogen.tasks.blocks import Condition, TaskBlock
from emogen.tasks.categorise import replay_export
from emogen.tasks.categorise.block import CategoriseBlock
from emogen.tasks.categorise.draw import BlockDraw
from emogen.tasks.categorise.export import CATEGORISE_TABLES
from emogen.tasks.categorise.faces import FileFaces, block_files
from emogen.tasks.categorise.replay import check_stimulus
from emogen.tasks.categorise.tables import ResponseRow, StimulusRow
from emogen.tasks.categorise.view import (
    CategoriseResult,
    CategoriseView,
    categorise_view,
    check_answer,
)
from emogen.tasks.errors import StepConflict
from emogen.tasks.protocol import (
    ExportedStudy,
    FaceView,
    MadeFace,
    Millis,
    Outcome,
    Points,
    Replayed,
    TaskEnv,
    TrialCommand,
)
from emogen.tasks.records import TrialRow, fields_of, server_ms, utcnow

#: The face id a categorise trial's one face has in its view (and its PNG's URL).
FACE_ID = 0


class Answer(TrialCommand):
    """The answer to a categorise trial's face: one of the labels it offered (or ``none`` where
    the block offers "none of these"), and the intensity / confidence ratings the block asks."""

    command: Literal["answer"]
    label: Annotated[str, Field(min_length=1, max_length=64)]
    intensity: Points | None = None
    confidence: Points | None = None
    #: Page's time from receiving the face to it drawn.
    load_ms: Millis | None = None


def _stimulus(db: Session, row: TrialRow) -> StimulusRow | None:
    return db.scalar(select(StimulusRow).where(StimulusRow.trial_id == row.id))


class CategoriseTask:
    """One face, one label (and the ratings the block asks)."""

    name: ClassVar[str] = "categorise"
    block: ClassVar[type[TaskBlock]] = CategoriseBlock
    commands: ClassVar[tuple[type[TrialCommand], ...]] = (Answer,)
    view_type: ClassVar[type] = CategoriseView
    result_type: ClassVar[type] = CategoriseResult
    tables: ClassVar[tuple[type, ...]] = (StimulusRow, ResponseRow)
    #: categorise_responses: each face shown and its answer (:mod:`.export`)
    export_tables: ClassVar[tuple[Any, ...]] = CATEGORISE_TABLES
    #: what the default instructions say of its blocks (after "In this study " or "In another
    #: part of the study ")
    instructions: ClassVar[str] = (
        "you will see one face at a time. Choose the emotion it shows (the number keys 1–9 "
        "choose too); where you are asked, also say how intense the expression is and how sure "
        "you are, then press “Continue”."
    )
    #: one face, a label, perhaps two ratings: 4–8 s (an assumption: no published figure)
    screens: ClassVar[dict[str, tuple[float, float]]] = {"categorise": (4.0, 8.0)}

    def screens_of(self, condition: Condition, generations: int) -> dict[str, int]:
        return {"categorise": 1}

    def prepare(self, ctx: Any, k: int, block: CategoriseBlock) -> dict[str, FileFaces]:
        return block_files(ctx, k, block)

    def rows(self, prepared: dict[str, FileFaces]) -> int | None:
        table = prepared.get("file")
        return None if table is None else len(table.weights)

    def start(self, env: TaskEnv, db: Session, row: TrialRow, session_id: int) -> Outcome:
        """The trial is shown now: its block's faces drawn first if they are not yet."""
        stim = _stimulus(db, row)
        if stim is None:
            BlockDraw(env, db, session_id, row.block).store()
            stim = _stimulus(db, row)
        now = utcnow()
        row.status = "active"
        row.started_at = now
        if stim is not None:
            stim.shown_at = now
        return Outcome()

    def accept(self, env: TaskEnv, db: Session, row: TrialRow, cmd: TrialCommand) -> Outcome:
        """Store the answer to the trial's face (checked against the labels it offered)."""
        if not isinstance(cmd, Answer):  # pragma: no cover - the study checks the command
            raise StepConflict(f"a categorise trial takes an answer; got {cmd.command}")
        if row.status != "active":  # pragma: no cover - a done trial is no longer current
            raise StepConflict(f"trial {row.position + 1} is not waiting for an answer")
        stim = _stimulus(db, row)
        if stim is None:  # pragma: no cover - stored when the trial started
            raise StepConflict(f"trial {row.position + 1} has no face stored; reload the page")
        block = env.block(row)
        offered = json.loads(stim.labels)
        position = check_answer(block, offered, cmd.label, cmd.intensity, cmd.confidence)
        now = utcnow()
        db.add(
            ResponseRow(
                **fields_of(cmd, ResponseRow),  # the answer as sent: label, ratings, load_ms
                trial_id=row.id,
                label_position=position,
                submitted_at=now,
                server_response_ms=server_ms(now, stim.shown_at, cmd.load_ms),
                client_response_ms=cmd.response_ms,
                step_key=cmd.key,
            )
        )
        row.status = "done"
        row.finished_at = now
        return Outcome(done=True)

    def view(self, env: TaskEnv, db: Session, row: TrialRow, shown: Any) -> dict[str, Any]:
        """The face and the labels in their order (never the face's source or the emotion it
        was made for)."""
        stim = _stimulus(db, row)
        if stim is None:  # pragma: no cover - stored when the trial started
            raise StepConflict(f"trial {row.position + 1} has no face stored; reload the page")
        face: FaceView = {"id": FACE_ID, "weights": json.loads(stim.weights)}
        return dict(categorise_view(env.block(row), face, json.loads(stim.labels)))

    def prompt(self, env: TaskEnv, row: TrialRow) -> str:
        return str(env.block(row).question)

    def face(
        self, env: TaskEnv, db: Session, row: TrialRow, face_id: int
    ) -> tuple[str, str] | None:
        stim = _stimulus(db, row)
        if stim is None or face_id != FACE_ID:
            return None
        return stim.weights, stim.identity

    def result(self, env: TaskEnv, db: Session, row: TrialRow) -> dict[str, Any] | None:
        """Once answered: the label given and the face's weights (never the emotion it was
        made for, nor whose face it is)."""
        if row.status != "done":
            return None
        answer = db.scalar(select(ResponseRow.label).where(ResponseRow.trial_id == row.id))
        stim = _stimulus(db, row)
        if answer is None or stim is None:
            return None
        return {"task": self.name, "label": answer, "weights": json.loads(stim.weights)}

    def made_faces(self, db: Session, where: Sequence[Any]) -> list[MadeFace]:
        return []  # a label, not a face

    def replay(self, env: TaskEnv, db: Session, row: TrialRow, rig: Any) -> Replayed:
        return check_stimulus(env, db, row, rig)

    #: the faces shown and the answers (:mod:`emogen.tasks.categorise.replay_export`)
    replay_tables: ClassVar[tuple[str, ...]] = replay_export.TABLES

    def replay_exported(self, env: TaskEnv, study: ExportedStudy) -> dict[int, list[Replayed]]:
        """What the export lets us rebuild from the trials' seeds, checked; what it does not,
        said (:mod:`emogen.tasks.categorise.replay_export`)."""
        return replay_export.replay_exported(env, study)

    def export_size(self, db: Session, sessions: Any) -> dict[int, int]:
        """A response row per trial shown."""
        query = (
            select(TrialRow.session_id, func.count(StimulusRow.id))
            .join(StimulusRow, StimulusRow.trial_id == TrialRow.id)
            .where(TrialRow.session_id.in_(sessions))
            .group_by(TrialRow.session_id)
        )
        return {int(sid): int(n) for sid, n in db.execute(query)}

    def simulate(self, who: Any, view: dict[str, Any], trial: int) -> dict[str, Any]:
        """The judge's label for the face, with the ratings the block asks."""
        points = (view["intensity"] or view["confidence"] or {"points": 7})["points"]
        label, intensity, confidence = who.judge.categorise(
            np.asarray(view["face"]["weights"]), view["labels"], points
        )
        return {
            "command": "answer",
            "trial": trial,
            "label": label,
            "intensity": intensity if view["intensity"] else None,
            "confidence": confidence if view["confidence"] else None,
        }

    def state_facts(self, state: str | None) -> dict[str, Any]:
        return {}

    def notes(self, db: Session, sessions: Any, k: int, block: CategoriseBlock) -> list[str]:
        """The share of others' faces that were fallback faces so far (when any were)."""
        query = (
            select(StimulusRow.fallback, func.count())
            .join(TrialRow, StimulusRow.trial_id == TrialRow.id)
            .where(
                TrialRow.session_id.in_(sessions),
                TrialRow.block == k,
                StimulusRow.source == "other",
            )
            .group_by(StimulusRow.fallback)
        )
        counts = {bool(f): int(n) for f, n in db.execute(query)}
        fell, total = counts.get(True, 0), sum(counts.values())
        if not fell:
            return []
        return [
            f"block {k + 1}: {fell} of the {total} others' faces drawn so far "
            f"({fell / total:.0%}) were fallback faces (no other session was complete when the "
            "participant reached the block): those participants drop out of the own-vs-others "
            "comparison. A pool of others' faces (others_pool = a pilot's export) prevents it"
        ]

    def shows(self, block: Any, config: Any) -> dict[str, Any]:
        """The labels offered (each trial in its own order), "none of these", the points of the
        intensity and confidence ratings asked (None: not asked) and the identities of the faces
        (as each trial's record says its own) — never whose faces they are, nor what for."""
        return {
            "labels": list(block.labels),
            "identities": list(block.identities),
            "none_option": block.none_option,
            "intensity_points": block.points if block.intensity else None,
            "confidence_points": block.points if block.confidence else None,
        }

    def progress_step(
        self, status: str, generation: int, generations: int
    ) -> tuple[str, int | None]:
        return self.name, None
