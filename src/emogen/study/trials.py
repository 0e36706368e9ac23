"""A trial's GA engine: started from the trial's seed, restored from its stored state, and every
population it makes stored (genes, full weights, ids, parents, operators) before it is shown."""

from __future__ import annotations

import threading
from collections import OrderedDict

import numpy as np
from sqlalchemy import insert
from sqlalchemy.orm import Session

from emogen.ga.engine import Engine, Population
from emogen.ga.state import collision_solver_of_state, state_data
from emogen.study.context import StudyContext
from emogen.study.queries import Executor, TrialRecord
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

    An engine whose state a step has just stored is kept in memory (:meth:`keep`, the last
    ``keep_size``), keyed by that very state text and identity: the trial's next step, if this
    process serves it and the stored state is still that text, continues it instead of parsing
    and rebuilding it from JSON. The engine is deterministic and its state is the whole of it, so
    the two are the same engine (tests/study/test_prepared.py checks the stored generations
    against a plain engine); any other state (another worker moved the trial on, a restart)
    simply misses and is restored.

    It also remembers, per session token, the shown generation and engine state this process
    last stored for the session (:meth:`remember`, :meth:`latest`): a selection's GA work,
    done before its transaction, starts from that state without reading the database first.
    A guess, never trusted: the transaction uses that work only if the trial's stored state is
    still that very text (see ``SessionSteps.prepare_select``).
    """

    def __init__(
        self, ctx: StudyContext, correctors: StudyCorrectors, keep_size: int = 1024
    ) -> None:
        self.ctx = ctx
        self.correctors = correctors
        self.keep_size = keep_size
        self._kept: OrderedDict[tuple[str, str], Engine] = OrderedDict()
        self._latest: OrderedDict[str, tuple[int, int, int, str, str]] = OrderedDict()
        self._kept_lock = threading.Lock()

    def remember(self, token: str, trial: TrialRow | TrialRecord | None) -> None:
        """The session ``token`` now shows ``trial``'s generation (stored in this transaction);
        forgotten when no generation is shown (None, or the trial waits for its rating)."""
        with self._kept_lock:
            self._latest.pop(token, None)
            if self.keep_size <= 0 or trial is None or trial.status != "active":
                return
            state = trial.engine_state
            if not state:
                return
            where = (trial.position, trial.attempt, trial.generation)
            self._latest[token] = (*where, trial.identity, state)
            while len(self._latest) > self.keep_size:
                self._latest.popitem(last=False)

    def latest(
        self, token: str, trial: int, attempt: int, generation: int
    ) -> tuple[str, str] | None:
        """(engine state, identity) this process last stored for the session, if it is of
        that trial, attempt and generation."""
        with self._kept_lock:
            known = self._latest.get(token)
        if known is None or known[:3] != (trial, attempt, generation):
            return None
        return known[4], known[3]

    def keep(self, state: str, identity: str, engine: Engine) -> None:
        """Keep ``engine``, whose ``to_json()`` is ``state``, for the trial's next step (it must
        not be changed afterwards: the next step takes it)."""
        if self.keep_size <= 0 or engine.done:
            return
        with self._kept_lock:
            self._kept[(identity, state)] = engine
            self._kept.move_to_end((identity, state))
            while len(self._kept) > self.keep_size:
                self._kept.popitem(last=False)

    def restore(self, row: TrialRow | TrialRecord) -> Engine:
        """The trial's engine, restored from its stored state."""
        return self.restore_state(row.engine_state or "", row.identity)

    def restore_state(self, state: str, identity: str) -> Engine:
        """An engine of the study's trial of ``identity`` restored from a stored state, with
        the collision solver the state was recorded with (a trial is corrected one way); the
        kept engine in exactly that state if there is one (taken: one step continues it)."""
        with self._kept_lock:
            kept = self._kept.pop((identity, state), None)
        if kept is not None:
            return kept
        data = state_data(state)
        corrector = self.correctors(identity, collision_solver_of_state(data))
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
        row.attempt = engine.trial
        row.generation = engine.generation
        shown = store_population(db, row, engine.ask())
        row.engine_state = engine.to_json()
        self.keep(row.engine_state, row.identity, engine)
        return shown


def store_population(
    db: Executor, trial: TrialRow | TrialRecord, population: Population
) -> ShownPopulation:
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
