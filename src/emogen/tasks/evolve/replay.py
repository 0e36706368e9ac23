"""Replay of an evolve trial: the GA engine rebuilt from the trial's seed and driven through the
recorded selections and restarts in the order they happened; every population it makes is
compared with the one stored: face ids, parent ids, operators and genes exactly, full weights
within floating-point rounding (:mod:`emogen.tasks.rounding`; the largest deviation is reported).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from sqlalchemy import select
from sqlalchemy.orm import Session, selectinload

from emogen.errors import EmoGenError
from emogen.ga.engine import Engine, stream_of_state
from emogen.ga.state import collision_solver_of_state, genome_of_state
from emogen.tasks.evolve.tables import FaceCurveRow, PopulationRow, RestartRow, SelectionRow
from emogen.tasks.protocol import Replayed, TaskEnv
from emogen.tasks.records import TrialRow
from emogen.tasks.rounding import WEIGHT_TOLERANCE, weight_deviation, within_rounding
from emogen.tasks.weights import full_weights


@dataclass(frozen=True)
class StoredFaces:
    """One stored population, as arrays: from the database or from exported tables.

    ids, parents (n, 2), operators : (n,); genes : (n, n_genes), or (n, n_genes, 6) for dynamic
    faces (amplitudes with their timing); weights : (n, n_columns); keyframes : a dynamic
    face's keyframe correctives (n, F, C), if it was corrected.
    """

    ids: np.ndarray
    parents: np.ndarray
    operators: list[str]
    genes: np.ndarray
    weights: np.ndarray
    keyframes: np.ndarray | None = None

    @classmethod
    def of_row(
        cls, stored: PopulationRow, curves: dict[tuple[int, int], FaceCurveRow] | None = None
    ) -> StoredFaces:
        faces = stored.faces
        mine = [(curves or {}).get((stored.id, f.position)) for f in faces]
        if mine and all(c is not None for c in mine):
            return cls._dynamic(cls.of_row(stored), [c for c in mine if c is not None])
        return cls(
            ids=np.array([f.face_id for f in faces], dtype=np.int64),
            parents=np.array([(f.parent_a, f.parent_b) for f in faces], dtype=np.int64),
            operators=[f.operator for f in faces],
            genes=np.array([json.loads(f.genes) for f in faces], dtype=np.float64),
            weights=np.array([json.loads(f.weights) for f in faces], dtype=np.float64),
        )

    @classmethod
    def _dynamic(cls, faces: StoredFaces, curves: list[FaceCurveRow]) -> StoredFaces:
        timing = np.array([json.loads(c.timing) for c in curves], dtype=np.float64)
        keyed = [json.loads(c.keyframe_correctives) for c in curves]
        genes = np.concatenate([faces.genes[..., None], timing], axis=-1)
        keyframes = None if keyed[0] is None else np.array(keyed, dtype=np.float64)
        return replace(faces, genes=genes, keyframes=keyframes)


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
        # an export holds a dynamic face's amplitudes as its genes (its curves: face_curves)
        genes = pop.genes[i, :, 0] if stored.genes.ndim < pop.genes.ndim else pop.genes[i]
        if not np.array_equal(stored.genes[i], genes):
            what.append("genes")
        deviation = weight_deviation(stored.weights[i], weights[i])
        worst = max(worst, deviation)
        if stored.keyframes is not None:  # an export does not hold them
            keyed = _keyframe_deviation(stored, pop, i)
            deviation = max(deviation, keyed)
            if not within_rounding(keyed):
                what.append(f"keyframe correctives differ by up to {keyed:.3g}")
        if not within_rounding(deviation):
            what.append(f"weights differ by up to {deviation:.3g} (tolerance {WEIGHT_TOLERANCE:g})")
        if what:
            problems.append(f"{where}, position {i}: " + ", ".join(what))
    return n, problems, worst


def _keyframe_deviation(stored: StoredFaces, pop: Any, i: int) -> float:
    """The largest difference of a dynamic face's keyframe correctives (inf: one side lacks
    them, or they differ in shape)."""
    a, b = stored.keyframes, pop.keyframe_correctives
    if a is None or b is None or a[i].shape != b[i].shape:
        return float("inf")
    return weight_deviation(a[i].reshape(-1), b[i].reshape(-1))


def replay_trial(env: TaskEnv, db: Session, trial: TrialRow, rig: Any) -> Replayed:
    """Replay an evolve trial's populations (attempt by attempt, with its selections and
    restarts)."""
    report = Replayed()
    config, correctors = env.config, env.correctors
    pops = db.scalars(
        select(PopulationRow)
        .where(PopulationRow.trial_id == trial.id)
        .order_by(PopulationRow.attempt, PopulationRow.generation)
        .options(selectinload(PopulationRow.faces))
    ).all()
    if not pops:
        return report
    sels = {
        s.population_id: s
        for s in db.scalars(select(SelectionRow).where(SelectionRow.trial_id == trial.id))
    }
    restarts = {
        r.population_id
        for r in db.scalars(select(RestartRow).where(RestartRow.trial_id == trial.id))
    }
    curves = {
        (c.population_id, c.position): c
        for c in db.scalars(
            select(FaceCurveRow).where(FaceCurveRow.population_id.in_([p.id for p in pops]))
        )
    }
    try:
        engine = Engine(
            config.ga_for(trial.identity),
            rig,
            trial.seed,
            corrector=correctors(trial.identity, collision_solver_of_state(trial.engine_state)),
            stream=stream_of_state(trial.engine_state),  # as it was drawn
            genome=genome_of_state(trial.engine_state),
        )
        for p in pops:
            where = f"trial {trial.position + 1} attempt {p.attempt + 1} generation {p.generation}"
            if (engine.attempt, engine.generation) != (p.attempt, p.generation):
                report.problems.append(
                    f"{where}: replay is at attempt {engine.attempt + 1} generation "
                    f"{engine.generation}"
                )
                break
            n, problems, deviation = compare_population(
                where, StoredFaces.of_row(p, curves), engine
            )
            report.populations += 1
            report.faces += n
            report.problems += problems
            report.deviation = max(report.deviation, deviation)
            if p.id in sels:
                s = sels[p.id]
                engine.tell(s.elite_face_id, json.loads(s.other_face_ids))
            elif p.id in restarts:
                engine.reset()
            # else: the population still shown; nothing follows it
    except EmoGenError as exc:
        report.problems.append(f"trial {trial.position + 1}: replay failed: {exc}")
    return report
