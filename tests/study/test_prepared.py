"""A selection's GA work is done before its write transaction, and used only if still valid.

The stored generation must be the one a plain engine makes from the recorded seed and
selections (an independent :class:`Engine` driven here), whichever path made it.
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import pytest
from sqlalchemy import select

from emogen.ga.engine import Engine, correctives_of
from emogen.study.prepared import Prepared
from emogen.study.sessions import StudyService
from emogen.study.steps import Timing
from emogen.study.tables import FaceRow, PopulationRow, TrialRow
from tests.study.drive import choose, new_key, step_args


def stored_weights(service: StudyService, generation: int) -> np.ndarray:
    with service.store.read() as db:
        rows = db.scalars(
            select(FaceRow)
            .join(PopulationRow, FaceRow.population_id == PopulationRow.id)
            .where(PopulationRow.generation == generation, PopulationRow.attempt == 0)
            .order_by(FaceRow.position)
        ).all()
        return np.array([json.loads(r.weights) for r in rows])


def reference_weights(service: StudyService, ict_model: Any, selections: list[dict]) -> np.ndarray:
    """The generation a fresh engine makes from the first trial's seed and these selections."""
    with service.store.read() as db:
        trial = db.scalars(select(TrialRow).where(TrialRow.position == 0)).one()
        seed, identity = trial.seed, trial.identity
    engine = Engine(
        service.ctx.config.ga_for(identity),
        ict_model.rig,
        seed,
        corrector=correctives_of(ict_model),
    )
    for s in selections:
        engine.tell(s["elite"], s["others"])
    pop = engine.ask()
    return np.hstack([pop.weights, pop.correctives])


def test_a_prepared_selection_is_used_without_restoring_the_engine(
    service: StudyService, ict_model: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    token, _ = service.create_session("PREP-1")
    state = service.begin(token, new_key())
    elite, others = choose(state)
    restored_in_transaction: list[int] = []
    engines = service.steps.engines
    original = engines.restore
    monkeypatch.setattr(
        engines, "restore", lambda row: restored_in_transaction.append(1) or original(row)
    )
    state = service.select(token, new_key(), **step_args(state), elite=elite, others=others)
    assert restored_in_transaction == []  # the transaction used the prepared engine
    assert state["progress"]["generation"] == 1
    expected = reference_weights(service, ict_model, [{"elite": elite, "others": others}])
    np.testing.assert_array_equal(stored_weights(service, 1), expected)
    shown = np.array([f["weights"] for f in state["population"]["faces"]])
    np.testing.assert_array_equal(shown, expected)


def test_a_stale_preparation_is_not_used(service: StudyService, ict_model: Any) -> None:
    """Prepared from another state (the trial moved on meanwhile): the transaction does the
    work itself, and what it stores is the right generation, not the prepared one."""
    token, _ = service.create_session("PREP-2")
    state = service.begin(token, new_key())
    elite, others = choose(state)
    args = step_args(state)
    with service.store.read() as db:
        trial = db.scalars(select(TrialRow).where(TrialRow.position == 0)).one()
        real_state = trial.engine_state
    wrong = Engine.from_json(real_state, ict_model.rig, corrector=correctives_of(ict_model))
    wrong.tell(others[0], [elite])  # another selection: a different next generation
    stale = Prepared("a state the trial is not in", wrong, wrong.to_json())
    key = new_key()
    result = service.steps.run_plain(
        token, "select", key,
        {"trial": args["trial"], "attempt": args["attempt"], "generation": args["generation"],
         "elite": elite, "others": others, "response_ms": None},
        lambda conn, read: service.steps.select(conn, read, key=key, **args, elite=elite,
            others=others, timing=Timing(), prepared=stale),
    )  # fmt: skip
    expected = reference_weights(service, ict_model, [{"elite": elite, "others": others}])
    np.testing.assert_array_equal(stored_weights(service, 1), expected)
    shown = np.array([f["weights"] for f in result["population"]["faces"]])
    np.testing.assert_array_equal(shown, expected)
    wrong_weights = np.hstack([wrong.ask().weights, wrong.ask().correctives])
    assert not np.array_equal(wrong_weights, expected)  # the test would see the stale one


def test_nothing_is_prepared_for_a_step_that_does_not_fit(service: StudyService) -> None:
    token, _ = service.create_session("PREP-3")
    assert (
        service.steps.prepare_select(token, trial=0, attempt=0, generation=0, elite=0, others=[])
        is None
    )  # fmt: skip  (instructions)
    state = service.begin(token, new_key())
    elite, others = choose(state)
    args = step_args(state)
    assert service.steps.prepare_select(token, **{**args, "generation": 3}, elite=elite,
                                        others=others) is None  # fmt: skip
    assert service.steps.prepare_select(token, **args, elite=10_000, others=[]) is None
    assert service.steps.prepare_select("no-such-token-at-all", **args, elite=elite,
                                        others=others) is None  # fmt: skip
    assert service.steps.prepare_select(token, **args, elite=elite, others=others) is not None


def test_a_face_shown_again_is_not_corrected_again(ict_model: Any) -> None:
    """The remembering corrector answers exactly what the model's corrector answers for the
    whole batch, and corrects only the faces it has not corrected before (the kept elite)."""
    from emogen.config import GAConfig
    from emogen.study.weights import RememberingCorrector

    base = correctives_of(ict_model)
    rows: list[int] = []

    def counting(w: np.ndarray) -> tuple[tuple[str, ...], np.ndarray]:
        rows.append(len(w))
        return base(w)

    remembering = RememberingCorrector(counting, size=15)
    engine = Engine(GAConfig(), ict_model.rig, 21)
    for g in range(4):
        pop = engine.ask()
        names, values = remembering(pop.weights)
        ref_names, ref_values = base(pop.weights)  # the whole batch at once, independently
        assert names == ref_names
        np.testing.assert_array_equal(values, ref_values)
        engine.tell(int(pop.ids[g]), [int(pop.ids[g + 1])])
    # generation 0: 10 faces; then the elite (slot 1) is remembered: 9 (or fewer) new ones
    assert rows[0] == 10 and all(n <= 9 for n in rows[1:])
    assert len(remembering._rows) <= 15  # bounded


def stored_state(service: StudyService) -> str:
    with service.store.read() as db:
        return str(db.scalars(select(TrialRow).where(TrialRow.position == 0)).one().engine_state)


def reference_engine(service: StudyService, ict_model: Any, selections: list) -> Engine:
    with service.store.read() as db:
        trial = db.scalars(select(TrialRow).where(TrialRow.position == 0)).one()
        seed, identity = trial.seed, trial.identity
    engine = Engine(service.ctx.config.ga_for(identity), ict_model.rig, seed,
                    corrector=correctives_of(ict_model))  # fmt: skip
    for elite, others in selections:
        engine.tell(elite, others)
    return engine


@pytest.fixture
def long_service(db_url: str, ict_model: Any) -> Any:
    """The small study with five generations (room for several selections in a trial)."""
    from emogen.study.config import study_from_dict
    from emogen.study.storage import Store
    from tests.study.conftest import SMALL_STUDY
    from tests.study.drive import study_service

    store = Store(db_url)
    config = study_from_dict({**SMALL_STUDY, "ga": {**SMALL_STUDY["ga"], "generations": 5}})
    yield study_service(config, store, ict_model)
    store.dispose()


def test_the_next_step_continues_the_kept_engine_and_stores_what_a_plain_engine_makes(
    long_service: StudyService, ict_model: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    """After the first step no engine is parsed from JSON again (each step's engine is kept),
    and every stored generation and engine state is the plain engine's."""
    service = long_service
    token, _ = service.create_session("KEEP-1")
    state = service.begin(token, new_key())
    parsed: list[int] = []
    original = Engine.from_json.__func__  # type: ignore[attr-defined]
    monkeypatch.setattr(
        Engine,
        "from_json",
        classmethod(lambda cls, *a, **k: parsed.append(1) or original(cls, *a, **k)),
    )
    selections = []
    for g in range(1, 5):
        elite, others = choose(state)
        selections.append((elite, others))
        state = service.select(token, new_key(), **step_args(state), elite=elite, others=others)
        reference = reference_engine(service, ict_model, selections)
        assert stored_state(service) == reference.to_json()
        pop = reference.ask()
        np.testing.assert_array_equal(
            stored_weights(service, g), np.hstack([pop.weights, pop.correctives])
        )
    assert parsed == []


def test_a_kept_engine_of_another_state_is_not_used(
    long_service: StudyService, ict_model: Any
) -> None:
    """Two workers on one database: worker A keeps the engine of generation 1, worker B moves
    the trial on; A's next step must continue from the stored state, not from what it kept."""
    from tests.study.drive import study_service

    a = long_service
    b = study_service(a.ctx.config, a.store, ict_model)
    token, _ = a.create_session("KEEP-2")
    state = a.begin(token, new_key())
    selections = []
    first_kept = None
    for worker in (a, b, a, a):
        elite, others = choose(state, n_others=1 + len(selections) % 2)
        selections.append((elite, others))
        state = worker.select(token, new_key(), **step_args(state), elite=elite, others=others)
        assert stored_state(a) == reference_engine(a, ict_model, selections).to_json()
        if first_kept is None:  # the engine A kept after the first selection
            first_kept = next(reversed(a.steps.engines._kept.values()))
    pop = reference_engine(a, ict_model, selections).ask()
    shown = np.array([f["weights"] for f in state["population"]["faces"]])
    np.testing.assert_array_equal(shown, np.hstack([pop.weights, pop.correctives]))
    # B stored the state after the one A kept, so A's later steps restored that state and never
    # took the engine it kept (a key by trial or identity alone would have taken it)
    assert any(e is first_kept for e in a.steps.engines._kept.values())
    assert first_kept.generation == 1


def test_kept_engines_are_bounded_and_taken_once(service: StudyService, ict_model: Any) -> None:
    from emogen.config import GAConfig

    engines = service.steps.engines
    engines.keep_size = 2
    corrector = engines.correctors("generic")
    made = [Engine(GAConfig(), ict_model.rig, seed, corrector=corrector) for seed in (1, 2, 3)]
    for e in made:
        engines.keep(e.to_json(), "generic", e)
    assert len(engines._kept) == 2
    assert engines.restore_state(made[2].to_json(), "generic") is made[2]
    # taken: the same state again is restored afresh (a new engine, equal to it)
    again = engines.restore_state(made[2].to_json(), "generic")
    assert again is not made[2] and again.to_json() == made[2].to_json()
    # the oldest was dropped
    assert engines.restore_state(made[0].to_json(), "generic") is not made[0]
    # another identity's trial in the same state does not take it
    assert engines.restore_state(made[1].to_json(), "female-light") is not made[1]
    assert engines.restore_state(made[1].to_json(), "generic") is made[1]


def statements_during(service: StudyService, call: Any, **kwargs: Any) -> tuple[Any, list[str]]:
    """``call(**kwargs)``'s result and the SQL statements it runs on the service's database."""
    from sqlalchemy import event

    seen: list[str] = []

    def record(conn: Any, cursor: Any, statement: str, *args: Any) -> None:
        seen.append(statement)

    event.listen(service.store.engine, "before_cursor_execute", record)
    try:
        result = call(**kwargs)
    finally:
        event.remove(service.store.engine, "before_cursor_execute", record)
    return result, seen


def test_a_step_after_one_this_process_stored_is_prepared_without_a_read(
    long_service: StudyService, ict_model: Any
) -> None:
    """The state this process stored for the session (after begin, after each selection) is
    where the next selection's work starts: no statement before the transaction, and what is
    stored is still the plain engine's generation."""
    service = long_service
    token, _ = service.create_session("LATEST-1")
    state = service.begin(token, new_key())
    selections = []
    for _ in range(3):
        elite, others = choose(state)
        args = step_args(state)
        prepared, seen = statements_during(
            service, service.steps.prepare_select, token=token, **args, elite=elite, others=others
        )
        assert seen == []
        assert prepared is not None and prepared.engine_state == stored_state(service)
        selections.append((elite, others))
        state = service.select(token, new_key(), **args, elite=elite, others=others)
        assert stored_state(service) == reference_engine(service, ict_model, selections).to_json()
    # a session this process has not stored a step for: read from the database
    service.steps.engines._latest.clear()
    elite, others = choose(state)
    prepared, seen = statements_during(
        service, service.steps.prepare_select, token=token, **step_args(state), elite=elite,
        others=others,
    )  # fmt: skip
    reads = [s for s in seen if s.startswith("SELECT")]
    assert prepared is not None and len(reads) == 1 and "trials.engine_state" in reads[0]


def test_a_remembered_state_is_checked_by_the_transaction(
    service: StudyService, ict_model: Any
) -> None:
    """The remembered state is a guess: if the trial's stored state is another (here: made to
    differ), the transaction does the work from the stored one."""
    token, _ = service.create_session("LATEST-2")
    state = service.begin(token, new_key())
    elite, others = choose(state)
    args = step_args(state)
    engines = service.steps.engines
    where, (identity, real_state) = engines._latest[token][:3], engines._latest[token][3:]
    assert real_state == stored_state(service)
    other = Engine(service.ctx.config.ga_for(identity), ict_model.rig, 12345,
                   corrector=correctives_of(ict_model))  # fmt: skip
    engines._latest[token] = (*where, identity, other.to_json())
    prepared = service.steps.prepare_select(token, **args, elite=elite, others=others)
    assert prepared is not None and prepared.engine_state == other.to_json()  # the guess used
    state = service.select(token, new_key(), **args, elite=elite, others=others)
    expected = reference_weights(service, ict_model, [{"elite": elite, "others": others}])
    np.testing.assert_array_equal(stored_weights(service, 1), expected)
    other.tell(elite, others)
    assert not np.array_equal(np.hstack([other.ask().weights, other.ask().correctives]), expected)


def test_remembered_states_are_bounded_and_forgotten_without_a_shown_generation(
    service: StudyService,
) -> None:
    from emogen.study.queries import TrialRecord

    engines = service.steps.engines
    engines.keep_size = 2

    def trial(status: str, generation: int) -> TrialRecord:
        return TrialRecord(1, 1, 0, status, "joy", "generic", 0, generation, f"state-{generation}",
                           None)  # fmt: skip

    for n in range(3):
        engines.remember(f"t{n}", trial("active", n))
    assert list(engines._latest) == ["t1", "t2"]
    assert engines.latest("t2", 0, 0, 2) == ("state-2", "generic")
    assert engines.latest("t2", 0, 0, 1) is None  # another generation
    assert engines.latest("t2", 1, 0, 2) is None and engines.latest("t2", 0, 1, 2) is None
    engines.remember("t2", trial("rating", 3))  # the trial waits for its rating
    engines.remember("t1", None)  # the step showed nothing (the session ended)
    assert engines.latest("t2", 0, 0, 2) is None and engines._latest == {}
