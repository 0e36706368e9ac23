"""Replay a stored session: regenerate every population from its seeds and recorded selections,
and check every categorise trial's face against its source (:mod:`emogen.study.replay_stimuli`).

For each trial the GA engine is rebuilt from the trial's seed and driven through the recorded
selections and restarts in the order they happened; every population it makes is compared with
the one stored: face ids, parent ids, operators and genes exactly, full weights within
floating-point rounding (:mod:`emogen.study.rounding`; the largest deviation is reported).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from sqlalchemy import select
from sqlalchemy.orm import Session, selectinload

from emogen.errors import EmoGenError
from emogen.ga.engine import Engine, stream_of_state
from emogen.ga.state import collision_solver_of_state
from emogen.model.rig import Rig
from emogen.study.config import StudyConfig
from emogen.study.context import accepted_hashes
from emogen.study.errors import SessionNotFound
from emogen.study.replay_stimuli import check_stimulus
from emogen.study.rounding import WEIGHT_TOLERANCE, weight_deviation, within_rounding
from emogen.study.weights import StudyCorrectors, full_weights

if TYPE_CHECKING:
    from emogen.model.face import FaceModel

from emogen.study.storage import Store
from emogen.study.tables import (
    PopulationRow,
    RestartRow,
    SelectionRow,
    SessionRow,
    StudyRow,
    TrialRow,
)


@dataclass
class ReplayReport:
    session_id: int
    model_hash_matches: bool
    populations: int = 0
    faces: int = 0
    #: categorise trials' faces checked (:mod:`emogen.study.replay_stimuli`)
    stimuli: int = 0
    mismatches: list[str] = field(default_factory=list)
    #: largest deviation of a replayed weight from the stored one, relative to max(1, |w|)
    #: (:func:`emogen.study.rounding.weight_deviation`): 0 on the recording machine, rounding
    #: (≤ WEIGHT_TOLERANCE) on another CPU
    weight_deviation: float = 0.0

    def add(self, problems: list[str], deviation: float) -> None:
        """Record a check's problems and its largest weight deviation."""
        self.mismatches += problems
        self.weight_deviation = max(self.weight_deviation, deviation)

    @property
    def ok(self) -> bool:
        return self.model_hash_matches and not self.mismatches

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
            "mismatches": self.mismatches,
        }


@dataclass(frozen=True)
class StoredFaces:
    """One stored population, as arrays: from the database or from exported tables.

    ids, parents (n, 2), operators : (n,); genes : (n, n_genes); weights : (n, n_columns).
    """

    ids: np.ndarray
    parents: np.ndarray
    operators: list[str]
    genes: np.ndarray
    weights: np.ndarray

    @classmethod
    def of_row(cls, stored: PopulationRow) -> StoredFaces:
        faces = stored.faces
        return cls(
            ids=np.array([f.face_id for f in faces], dtype=np.int64),
            parents=np.array([(f.parent_a, f.parent_b) for f in faces], dtype=np.int64),
            operators=[f.operator for f in faces],
            genes=np.array([json.loads(f.genes) for f in faces], dtype=np.float64),
            weights=np.array([json.loads(f.weights) for f in faces], dtype=np.float64),
        )


def compare_population(
    where: str, stored: StoredFaces, engine: Engine
) -> tuple[int, list[str], float]:
    """Ask ``engine`` for its next population and compare it with ``stored``, face by face
    (ids, parents, operators and genes exactly; full weights within rounding):
    (faces, problems, largest weight deviation)."""
    pop = engine.ask()
    n = len(stored.ids)
    if n != len(pop):
        return 0, [f"{where}: stored {n} faces, replay made {len(pop)}"], 0.0
    weights = full_weights(pop)
    if stored.weights.shape != weights.shape:
        return (
            0,
            [
                f"{where}: stored {stored.weights.shape[1]} weights a face, "
                f"replay made {weights.shape[1]}"
            ],
            0.0,
        )
    problems = []
    worst = 0.0
    for i in range(n):
        what = []
        if int(stored.ids[i]) != int(pop.ids[i]):
            what.append(f"id {int(stored.ids[i])} vs {int(pop.ids[i])}")
        if tuple(int(x) for x in stored.parents[i]) != tuple(int(x) for x in pop.parent_ids[i]):
            what.append("parents")
        if stored.operators[i] != str(pop.operators[i]):
            what.append(f"operator {stored.operators[i]} vs {pop.operators[i]}")
        if not np.array_equal(stored.genes[i], pop.genes[i]):
            what.append("genes")
        deviation = weight_deviation(stored.weights[i], weights[i])
        worst = max(worst, deviation)
        if not within_rounding(deviation):
            what.append(f"weights differ by up to {deviation:.3g} (tolerance {WEIGHT_TOLERANCE:g})")
        if what:
            problems.append(f"{where}, position {i}: " + ", ".join(what))
    return n, problems, worst


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
    compared too).
    """
    with store.read() as db:
        sess = db.get(SessionRow, session_id)
        if sess is None:
            raise SessionNotFound(f"no session with id {session_id} in {store.describe()}")
        study = db.get(StudyRow, sess.study_id)
        if study is None:  # pragma: no cover - foreign key
            raise SessionNotFound(f"session {session_id} has no study")
        config = StudyConfig.model_validate(json.loads(study.config_json))
        report = ReplayReport(
            session_id, model_hash_matches=study.model_hash in accepted_hashes(model_hash, model)
        )
        correctors = StudyCorrectors(config, model)
        trials = db.scalars(
            select(TrialRow).where(TrialRow.session_id == sess.id).order_by(TrialRow.position)
        ).all()
        for trial in trials:
            if trial.task == "categorise":
                n, problems, deviation = check_stimulus(db, trial, config, rig, correctors)
                report.stimuli += n
                report.add(problems, deviation)
                continue
            _replay_trial(db, trial, config, rig, correctors, report)
    return report


def _replay_trial(
    db: Session,
    trial: TrialRow,
    config: StudyConfig,
    rig: Rig,
    correctors: StudyCorrectors,
    report: ReplayReport,
) -> None:
    """Replay an evolve trial's populations (attempt by attempt, with its selections and
    restarts) into ``report``."""
    pops = db.scalars(
        select(PopulationRow)
        .where(PopulationRow.trial_id == trial.id)
        .order_by(PopulationRow.attempt, PopulationRow.generation)
        .options(selectinload(PopulationRow.faces))
    ).all()
    if not pops:
        return
    sels = {
        s.population_id: s
        for s in db.scalars(select(SelectionRow).where(SelectionRow.trial_id == trial.id))
    }
    restarts = {
        r.population_id
        for r in db.scalars(select(RestartRow).where(RestartRow.trial_id == trial.id))
    }
    try:
        engine = Engine(
            config.ga_for(trial.identity),
            rig,
            trial.seed,
            corrector=correctors(trial.identity, collision_solver_of_state(trial.engine_state)),
            stream=stream_of_state(trial.engine_state),  # as it was drawn
        )
        for p in pops:
            where = f"trial {trial.position + 1} attempt {p.attempt + 1} generation {p.generation}"
            if (engine.attempt, engine.generation) != (p.attempt, p.generation):
                report.mismatches.append(
                    f"{where}: replay is at attempt {engine.attempt + 1} generation "
                    f"{engine.generation}"
                )
                break
            n, problems, deviation = compare_population(where, StoredFaces.of_row(p), engine)
            report.populations += 1
            report.faces += n
            report.add(problems, deviation)
            if p.id in sels:
                s = sels[p.id]
                engine.tell(s.elite_face_id, json.loads(s.other_face_ids))
            elif p.id in restarts:
                engine.reset()
            # else: the population still shown; nothing follows it
    except EmoGenError as exc:
        report.mismatches.append(f"trial {trial.position + 1}: replay failed: {exc}")
