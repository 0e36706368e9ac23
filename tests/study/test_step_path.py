"""Every step takes one path: the session locked, the trial's engine restored from its stored
JSON state, the step's rows written, committed before the answer. What it stores must be what
an independent, plain :class:`Engine` makes from the recorded seed and selections — whichever
worker served the step before (two services on one database here)."""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import pytest
from sqlalchemy import select

from emogen.ga.engine import Engine, correctives_of
from emogen.study.sessions import StudyService
from emogen.study.tables import TrialRow
from emogen.tasks.evolve.tables import FaceRow, PopulationRow
from tests.study.drive import choose, do, new_key, step_args


@pytest.fixture
def two_services(db_url: str, ict_model: Any) -> Any:
    """Two services (two workers) of the small study with five generations on one database."""
    from emogen.study.config import study_from_dict
    from emogen.study.storage import Store
    from tests.study.conftest import SMALL_STUDY
    from tests.study.drive import study_service

    config = study_from_dict({**SMALL_STUDY, "ga": {**SMALL_STUDY["ga"], "generations": 5}})
    stores = [Store(db_url), Store(db_url)]
    yield [study_service(config, store, ict_model) for store in stores]
    for store in stores:
        store.dispose()


def stored(service: StudyService, attempt: int, generation: int) -> tuple[str, np.ndarray]:
    """The first trial's engine state now, and the full weights of one of its generations."""
    with service.store.read() as db:
        state = db.scalars(select(TrialRow).where(TrialRow.position == 0)).one().engine_state
        rows = db.scalars(
            select(FaceRow)
            .join(PopulationRow, FaceRow.population_id == PopulationRow.id)
            .join(TrialRow, PopulationRow.trial_id == TrialRow.id)
            .where(
                TrialRow.position == 0,
                PopulationRow.attempt == attempt,
                PopulationRow.generation == generation,
            )
            .order_by(FaceRow.position)
        ).all()
        return str(state), np.array([json.loads(r.weights) for r in rows])


def test_each_step_stores_what_a_plain_engine_makes_whichever_worker_serves_it(
    two_services: list[StudyService], ict_model: Any
) -> None:
    a, b = two_services
    token, _ = a.create_session("PATH-1")
    state = do(a, "begin", token, new_key())
    with a.store.read() as db:
        trial = db.scalars(select(TrialRow).where(TrialRow.position == 0)).one()
        seed, identity = trial.seed, trial.identity
    reference = Engine(
        a.ctx.config.ga_for(identity), ict_model.rig, seed, corrector=correctives_of(ict_model)
    )
    pop = reference.ask()
    assert stored(a, 0, 0)[0] == reference.to_json()
    np.testing.assert_array_equal(stored(a, 0, 0)[1], np.hstack([pop.weights, pop.correctives]))
    # selections alternate between the workers; a restart after the second
    for g in range(1, 12):
        service = (a, b)[g % 2]
        elite, others = choose(state)
        state = do(
            service, "select", token, new_key(), **step_args(state), elite=elite, others=others
        )
        reference.tell(elite, others)
        if g == 2:
            state = do(service, "restart", token, new_key(), **step_args(state))
            reference.reset()
        if state["trial"]["status"] == "rating":
            assert reference.done
            break
        pop = reference.ask()
        where = (state["trial"]["attempt"], state["view"]["generation"])
        engine_state, weights = stored(service, *where)
        assert engine_state == reference.to_json()
        np.testing.assert_array_equal(weights, np.hstack([pop.weights, pop.correctives]))
        shown = np.array([f["weights"] for f in state["view"]["population"]["faces"]])
        np.testing.assert_array_equal(shown, weights)  # the answer shows what was stored
    assert state["trial"]["status"] == "rating"
