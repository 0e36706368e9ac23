"""The ``evolve`` task's storage: a trial's GA engine started from the trial's seed and restored
from its stored state, every population it makes stored (genes, full weights, ids, parents,
operators) before it is shown, and the reads its steps and views need."""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass, field
from datetime import datetime
from typing import Any

import numpy as np
from sqlalchemy import bindparam, func, insert, select
from sqlalchemy.orm import Session, selectinload

from emogen.ga.engine import Engine, Population
from emogen.ga.state import collision_solver_of_state, state_data
from emogen.tasks.evolve.tables import FaceCurveRow, FaceRow, PopulationRow, SelectionRow
from emogen.tasks.protocol import FaceView, MadeFace, TaskEnv
from emogen.tasks.records import TrialRow, core_table, numbers_json, utcnow
from emogen.tasks.weights import full_weights

_POPULATIONS = core_table(PopulationRow)
_INSERT_POPULATION = insert(_POPULATIONS).returning(_POPULATIONS.c.id)
_INSERT_FACES = insert(core_table(FaceRow))
_INSERT_CURVES = insert(core_table(FaceCurveRow))


@dataclass(frozen=True)
class ShownPopulation:
    """A population a step has just stored and shows, keyed by where it belongs."""

    trial_id: int
    attempt: int
    generation: int
    faces: list[FaceView]
    #: the trial's row, as the step left it
    trial: TrialRow | None = field(default=None, compare=False)
    #: its stored row's id, and a dynamic population's curves as stored (each face's timing
    #: (K, 5) and keyframe correctives (F, C) or None), so the view reads nothing back
    population_id: int | None = field(default=None, compare=False)
    curves: list[tuple[np.ndarray, np.ndarray | None]] | None = field(default=None, compare=False)


def new_engine(env: TaskEnv, row: TrialRow) -> Engine:
    """A trial's engine at its start, from the trial's seed, with its identity's corrector."""
    return Engine(
        env.config.ga_for(row.identity),
        env.ctx.rig,
        row.seed,
        corrector=env.correctors(row.identity),
        genome=env.block(row).genome(),
    )


def restore(env: TaskEnv, row: TrialRow) -> Engine:
    """The trial's engine, restored from its stored state (the one source of truth, whichever
    worker served the step before), with the collision solver the state was recorded with."""
    data = state_data(row.engine_state or "")
    corrector = env.correctors(row.identity, collision_solver_of_state(data))
    return Engine.from_json(data, env.ctx.rig, corrector=corrector)


def store_population(db: Session, trial: TrialRow, population: Population) -> ShownPopulation:
    """Store a population about to be shown; returns it as the view shows it.

    Plain inserts (the population's id returned by the insert), not ORM objects: nothing reads
    these rows back in the step, and the ORM's unit of work would cost more than the inserts."""
    pop_id = db.execute(
        _INSERT_POPULATION,
        {
            "trial_id": trial.id,
            "attempt": population.attempt,
            "generation": population.generation,
            "shown_at": utcnow(),
        },
    ).scalar_one()
    full = full_weights(population)
    if not (np.isfinite(full).all() and np.isfinite(population.genes).all()):
        raise ValueError("a population to store has non-finite genes or weights")
    weights: list[list[float]] = full.tolist()
    dynamic = population.genes.ndim == 3  # (n, K, 6): amplitudes here, curves beside
    genes: list[list[float]] = (population.genes[..., 0] if dynamic else population.genes).tolist()
    ids = population.ids.tolist()
    parents = population.parent_ids.tolist()
    operators = population.operators.tolist()
    db.execute(
        _INSERT_FACES,
        [
            {
                "population_id": pop_id,
                "position": i,
                "face_id": ids[i],
                "parent_a": parents[i][0],
                "parent_b": parents[i][1],
                "operator": operators[i],
                "genes": numbers_json(genes[i]),
                "weights": numbers_json(weights[i]),
            }
            for i in range(len(population))
        ],
    )
    curves = _store_curves(db, pop_id, population) if dynamic else None
    faces = [FaceView(id=i, weights=w) for i, w in zip(ids, weights, strict=True)]
    return ShownPopulation(
        trial.id, population.attempt, population.generation, faces, trial, pop_id, curves
    )


def _store_curves(
    db: Session, pop_id: int, population: Population
) -> list[tuple[np.ndarray, np.ndarray | None]]:
    """A dynamic population's curves: each face's timing and keyframe correctives (orjson: the
    same shortest round-trip decimals as ``json``; ``json.dumps`` of a population's keyframes,
    ten faces × 21 × 77 numbers, took 3–10 ms of a step, benchmarks/bench_step.py --dynamic).
    Returns them per face, as stored."""
    keyed = population.keyframe_correctives
    curves = [
        (population.genes[i, :, 1:], None if keyed is None else keyed[i])
        for i in range(len(population))
    ]
    db.execute(
        _INSERT_CURVES,
        [
            {
                "population_id": pop_id,
                "position": i,
                "timing": numbers_json(timing.tolist()),
                "keyframe_correctives": numbers_json(None if k is None else k.tolist()),
            }
            for i, (timing, k) in enumerate(curves)
        ],
    )
    return curves


_POPULATION_AT = select(PopulationRow).where(
    PopulationRow.trial_id == bindparam("trial_id"),
    PopulationRow.attempt == bindparam("attempt"),
    PopulationRow.generation == bindparam("generation"),
)
_POPULATION_AT_WITH_FACES = _POPULATION_AT.options(selectinload(PopulationRow.faces))


def population_at(
    db: Session, trial_id: int, attempt: int, generation: int, *, with_faces: bool = False
) -> PopulationRow | None:
    """The stored population of a trial's attempt and generation (its faces loaded if asked)."""
    query = _POPULATION_AT_WITH_FACES if with_faces else _POPULATION_AT
    return db.scalar(query, {"trial_id": trial_id, "attempt": attempt, "generation": generation})


def final_face(db: Session, trial: TrialRow) -> FaceRow | None:
    """The trial's final face (the last elite) in its current attempt."""
    return db.scalar(
        select(FaceRow)
        .join(PopulationRow, FaceRow.population_id == PopulationRow.id)
        .where(
            PopulationRow.trial_id == trial.id,
            PopulationRow.attempt == trial.attempt,
            FaceRow.face_id == trial.final_face_id,
        )
        .order_by(PopulationRow.generation.desc())
        .limit(1)
    )


def last_selection_time(db: Session, trial_id: int) -> datetime | None:
    return db.scalar(
        select(SelectionRow.submitted_at)
        .where(SelectionRow.trial_id == trial_id)
        .order_by(SelectionRow.id.desc())
        .limit(1)
    )


def shown_face(db: Session, row: TrialRow, face_id: int) -> FaceRow | None:
    """The row of a face the trial shows now: the generation shown, or while the trial waits
    for its rating its final face (an earlier generation's faces are not served)."""
    if row.status == "rating":
        if face_id != row.final_face_id:
            return None
        shown = PopulationRow.generation <= row.generation
    else:
        shown = PopulationRow.generation == row.generation
    return db.scalar(
        select(FaceRow)
        .join(PopulationRow, FaceRow.population_id == PopulationRow.id)
        .where(
            PopulationRow.trial_id == row.id,
            PopulationRow.attempt == row.attempt,
            shown,
            FaceRow.face_id == face_id,
        )
        .order_by(PopulationRow.generation.desc())
        .limit(1)
    )


def final_faces(db: Session, task: str, where: Sequence[Any]) -> list[MadeFace]:
    """The final faces of the finished trials of ``task`` matching ``where``: the final face's
    row in the trial's last attempt (its latest generation, where it was shown again)."""
    rows = db.execute(
        select(TrialRow, FaceRow)
        .join(PopulationRow, PopulationRow.trial_id == TrialRow.id)
        .join(FaceRow, FaceRow.population_id == PopulationRow.id)
        .where(
            *where,
            TrialRow.task == task,
            TrialRow.status == "done",
            PopulationRow.attempt == TrialRow.attempt,
            FaceRow.face_id == TrialRow.final_face_id,
        )
        .order_by(PopulationRow.generation)
    ).all()
    latest = {t.id: (t, f) for t, f in rows}  # the last generation's row wins
    return [
        {
            "session_id": t.session_id,
            "trial": t.position,
            "condition": t.condition,
            "emotion": t.emotion,
            "identity": t.identity,
            "face_id": f.face_id,
            "genes": json.loads(f.genes),
            "weights": json.loads(f.weights),
        }
        for t, f in latest.values()
    ]


def faces_per_session(db: Session, sessions: Any) -> dict[int, int]:
    """The faces stored for each session in ``sessions`` (a SELECT of session ids)."""
    query = (
        select(TrialRow.session_id, func.count(FaceRow.id))
        .join(PopulationRow, PopulationRow.trial_id == TrialRow.id)
        .join(FaceRow, FaceRow.population_id == PopulationRow.id)
        .where(TrialRow.session_id.in_(sessions))
        .group_by(TrialRow.session_id)
    )
    return {int(sid): int(n) for sid, n in db.execute(query)}
