"""Replay a stored session: every trial re-run by its task from its seed and recorded commands
and compared with its records (:meth:`emogen.tasks.protocol.Task.replay`: what each task regenerates or checks is its own);
discrete
things exactly, weights within floating-point rounding (:mod:`emogen.tasks.rounding`; the
largest deviation is reported).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from types import SimpleNamespace
from typing import TYPE_CHECKING, Any

from sqlalchemy import select

from emogen.model.load import model_for_recorded_hash
from emogen.model.rig import Rig
from emogen.study.config import StudyConfig
from emogen.study.context import accepted_hashes
from emogen.study.errors import SessionNotFound
from emogen.study.storage import Store
from emogen.study.tables import SessionRow, StudyRow, TrialRow
from emogen.study.tasking import made_faces
from emogen.study.weights import StudyCorrectors
from emogen.tasks.protocol import Replayed, TaskEnv
from emogen.tasks.registry import task_named
from emogen.tasks.rounding import WEIGHT_TOLERANCE

if TYPE_CHECKING:
    from emogen.model.face import FaceModel


@dataclass
class ReplayReport:
    session_id: int
    model_hash_matches: bool
    populations: int = 0
    faces: int = 0
    #: stimuli checked against their source
    stimuli: int = 0
    mismatches: list[str] = field(default_factory=list)
    #: largest deviation of a replayed weight from the stored one, relative to max(1, |w|)
    #: (:func:`emogen.tasks.rounding.weight_deviation`): 0 on the recording machine, rounding
    #: (≤ WEIGHT_TOLERANCE) on another CPU
    weight_deviation: float = 0.0
    #: what the tasks rebuilt and compared, by what it is (each task names its own kinds)
    checked: dict[str, int] = field(default_factory=dict)
    #: what could not be checked, each saying what and why: never counted as matching
    unchecked: list[str] = field(default_factory=list)

    def add(self, problems: list[str], deviation: float) -> None:
        """Record a check's problems and its largest weight deviation."""
        self.mismatches += problems
        self.weight_deviation = max(self.weight_deviation, deviation)

    def take(self, done: Replayed) -> None:
        """Add a task's replay of a trial (or of a session's trials)."""
        self.populations += done.populations
        self.faces += done.faces
        self.stimuli += done.stimuli
        self.add(done.problems, done.deviation)
        for what, n in done.checked.items():
            self.checked[what] = self.checked.get(what, 0) + n
        self.unchecked += done.unchecked

    @property
    def ok(self) -> bool:
        """Everything recorded was checked and matches (something unchecked is not ok)."""
        return self.model_hash_matches and not self.mismatches and not self.unchecked

    def to_dict(self) -> dict[str, Any]:
        return {
            "session_id": self.session_id,
            "ok": self.ok,
            "model_hash_matches": self.model_hash_matches,
            "populations": self.populations,
            "faces": self.faces,
            "stimuli": self.stimuli,
            "weight_deviation": self.weight_deviation,
            "weight_tolerance": WEIGHT_TOLERANCE,
            "checked": self.checked,
            "mismatches": self.mismatches,
            "unchecked": self.unchecked,
        }


def study_of_session(store: Store, session_id: int) -> StudyConfig:
    """The study config a session was recorded under."""
    with store.read() as db:
        sess = db.get(SessionRow, session_id)
        if sess is None:
            raise SessionNotFound(f"no session with id {session_id} in {store.describe()}")
        study = db.get(StudyRow, sess.study_id)
        if study is None:  # pragma: no cover - foreign key
            raise SessionNotFound(f"session {session_id} has no study")
        return StudyConfig.model_validate(json.loads(study.config_json))


def replay_session(
    store: Store,
    session_id: int,
    rig: Rig,
    model_hash: str,
    *,
    model: FaceModel | None = None,
) -> ReplayReport:
    """Regenerate every population of session ``session_id`` and compare it with the stored one.

    model : the face model; needed for a study that corrects faces (``correct = true``), whose
    replayed populations are corrected as they were when shown (and their corrective weights
    compared too). A study recorded with an older packaged rig replays with that rig
    (:func:`~emogen.model.load.model_for_recorded_hash`).
    """
    with store.read() as db:
        sess = db.get(SessionRow, session_id)
        if sess is None:
            raise SessionNotFound(f"no session with id {session_id} in {store.describe()}")
        study = db.get(StudyRow, sess.study_id)
        if study is None:  # pragma: no cover - foreign key
            raise SessionNotFound(f"session {session_id} has no study")
        config = StudyConfig.model_validate(json.loads(study.config_json))
        if model is not None and model.model_hash == model_hash:  # an older packaged rig?
            model = model_for_recorded_hash(model, study.model_hash)
            rig, model_hash = model.rig, model.model_hash
        report = ReplayReport(
            session_id, model_hash_matches=study.model_hash in accepted_hashes(model_hash, model)
        )
        ctx = SimpleNamespace(config=config, rig=rig, conditions=(), accepted=(sess.study_id,))
        env = TaskEnv(ctx=ctx, correctors=StudyCorrectors(config, model), made_faces=made_faces)
        trials = db.scalars(
            select(TrialRow).where(TrialRow.session_id == sess.id).order_by(TrialRow.position)
        ).all()
        for trial in trials:
            report.take(task_named(trial.task).replay(env, db, trial, rig))
    return report
