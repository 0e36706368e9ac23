"""A trial's GA engine: started from the trial's seed, restored from its stored state, and every
population it makes stored (genes, full weights, ids, parents, operators) before it is shown."""

from __future__ import annotations

import numpy as np
from sqlalchemy import insert
from sqlalchemy.orm import Session

from emogen.ga.engine import Engine, Population
from emogen.ga.state import collision_solver_of_state, state_data
from emogen.study.context import StudyContext
from emogen.study.tables import (
    FaceRow,
    PopulationRow,
    SessionRow,
    TrialRow,
    core_table,
    numbers_json,
    utcnow,
)
from emogen.study.view import FaceView, ShownPopulation
from emogen.study.weights import StudyCorrectors, full_weights

_POPULATIONS = core_table(PopulationRow)
_INSERT_POPULATION = insert(_POPULATIONS).returning(_POPULATIONS.c.id)
_INSERT_FACES = insert(core_table(FaceRow))


class TrialEngines:
    """Makes and restores the engines of a study's trials, each with its identity's corrector.

    A step restores the trial's engine from its stored JSON state, the one source of truth
    (whichever worker served the step before): no engine is kept in memory between steps."""

    #: the task whose trials it runs (:class:`emogen.tasks.protocol.TaskRunner`)
    task = "evolve"

    def __init__(self, ctx: StudyContext, correctors: StudyCorrectors) -> None:
        self.ctx = ctx
        self.correctors = correctors

    def restore(self, row: TrialRow) -> Engine:
        """The trial's engine, restored from its stored state, with the collision solver the
        state was recorded with (a trial is corrected one way)."""
        data = state_data(row.engine_state or "")
        corrector = self.correctors(row.identity, collision_solver_of_state(data))
        return Engine.from_json(data, self.ctx.rig, corrector=corrector)

    def start(self, db: Session, sess: SessionRow, row: TrialRow) -> ShownPopulation:
        """Start the session's evolve trial ``row``: its generation 0 is made and stored."""
        engine = Engine(
            self.ctx.config.ga_for(row.identity),
            self.ctx.rig,
            row.seed,
            corrector=self.correctors(row.identity),
        )
        row.status = "active"
        row.started_at = utcnow()
        row.attempt = engine.attempt
        row.generation = engine.generation
        shown = store_population(db, row, engine.ask())
        row.engine_state = engine.to_json()
        return shown


def store_population(db: Session, trial: TrialRow, population: Population) -> ShownPopulation:
    """Store a population about to be shown; returns it as the view shows it.

    Plain inserts (the population's id returned by the insert), not ORM objects: nothing reads
    these rows back in the step, and the ORM's unit of work would cost more than the inserts."""
    pop_id = db.execute(
        _INSERT_POPULATION,
        {
            "trial_id": trial.id,
            "attempt": population.trial,
            "generation": population.generation,
            "shown_at": utcnow(),
        },
    ).scalar_one()
    full = full_weights(population)
    if not (np.isfinite(full).all() and np.isfinite(population.genes).all()):
        raise ValueError("a population to store has non-finite genes or weights")
    weights: list[list[float]] = full.tolist()
    genes: list[list[float]] = population.genes.tolist()
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
    faces = [FaceView(id=i, weights=w) for i, w in zip(ids, weights, strict=True)]
    return ShownPopulation(trial.id, population.trial, population.generation, faces, trial)
