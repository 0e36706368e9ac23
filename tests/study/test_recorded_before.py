"""A study recorded before the GA was written once over runs (engine stream 1) and before the
eq. 5 solvers were numbered (collision solver 1) still replays, and a session left in the middle
then continues with the stream and the solver it was drawn and corrected with."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from sqlalchemy import select

from emogen.config import GAConfig
from emogen.ga.engine import Engine, stream_of_state
from emogen.ga.state import collision_solver_of_state
from emogen.model.load import model_for_recorded_hash
from emogen.study.config import StudyConfig
from emogen.study.export import export_tables
from emogen.study.replay import replay_session
from emogen.study.storage import Store
from emogen.study.tables import SessionRow, StudyRow, TrialRow
from tests.study.drive import run_to_end, service_caller, study_service

RECORDED = Path(__file__).parents[1] / "data" / "study_stream1.sqlite"
OLD_2 = "_6O84B37ReuaCQMLGuN28Qw1lBIuGAFL"  # OLD-2's link: stopped in generation 3 of trial 1


def _open(tmp_path: Path) -> Store:
    copy = tmp_path / "recorded.sqlite"
    shutil.copyfile(RECORDED, copy)
    return Store(f"sqlite:///{copy}")


def _sessions(store: Store) -> dict[str, int]:
    with store.read() as db:
        return {s.participant_id: s.id for s in db.scalars(select(SessionRow))}


def _streams(store: Store, session_id: int) -> list[int]:
    with store.read() as db:
        rows = db.scalars(
            select(TrialRow).where(TrialRow.session_id == session_id).order_by(TrialRow.position)
        )
        return [stream_of_state(r.engine_state) for r in rows]


def _solvers(store: Store, session_id: int) -> list[int | None]:
    """The collision solver each trial's stored state records (None: not recorded)."""
    with store.read() as db:
        rows = db.scalars(
            select(TrialRow).where(TrialRow.session_id == session_id).order_by(TrialRow.position)
        )
        return [json.loads(r.engine_state).get("collision_solver") for r in rows]


def _state(store: Store, session_id: int) -> str:
    with store.read() as db:
        return db.scalars(
            select(TrialRow.engine_state).where(TrialRow.session_id == session_id)
        ).first()


def test_recorded_study_replays_exactly(tmp_path: Path, ict_model) -> None:
    store = _open(tmp_path)
    try:
        ids = _sessions(store)
        assert set(ids) == {"OLD-1", "OLD-2"}
        assert _streams(store, ids["OLD-1"]) == [1, 1]
        assert _solvers(store, ids["OLD-1"]) == [None, None]  # recorded before: solver 1
        assert collision_solver_of_state(_state(store, ids["OLD-1"])) == 1
        for participant, populations in (("OLD-1", 13), ("OLD-2", 4)):
            report = replay_session(
                store, ids[participant], ict_model.rig, ict_model.model_hash, model=ict_model
            )
            assert report.mismatches == [], report.mismatches
            assert report.populations == populations and report.faces == 10 * populations
            # recorded with the version-1 model hash: still this model (emogen.model.model_hash)
            assert report.model_hash_matches and report.ok
    finally:
        store.dispose()


def test_a_session_recorded_mid_trial_continues_and_replays(tmp_path: Path, ict_model) -> None:
    store = _open(tmp_path)
    try:
        with store.read() as db:
            study = db.scalars(select(StudyRow)).one()
            config = StudyConfig.model_validate(json.loads(study.config_json))
        service = study_service(config, store, ict_model)
        state = service.state(OLD_2)
        assert state["view"]["generation"] == 3
        assert run_to_end(state, service_caller(service, OLD_2))["stage"] == "done"
        old_2 = _sessions(store)["OLD-2"]
        # trial 1 goes on with the stream it began with; trial 2 began after the upgrade
        assert _streams(store, old_2) == [1, 2]
        # and with the collision solver it was corrected with (2: the current one)
        assert _solvers(store, old_2) == [1, 2]
        trials = export_tables(store)["trials"]
        solvers = trials.set_index(["participant_id", "trial"])["collision_solver"]
        assert solvers[("OLD-2", 0)] == 1 and solvers[("OLD-2", 1)] == 2
        assert solvers[("OLD-1", 0)] == 1 and solvers[("OLD-1", 1)] == 1
        report = replay_session(store, old_2, ict_model.rig, ict_model.model_hash, model=ict_model)
        assert report.mismatches == [], report.mismatches
        assert report.populations == 10
    finally:
        store.dispose()


def test_recorded_selections_replay_with_the_old_key(tmp_path: Path, ict_model) -> None:
    """A ``/1`` state names the engine's attempt ``trial`` (in the state, its selections and
    populations): its selection list still replays to the state it was stored with."""
    store = _open(tmp_path)
    try:
        old = json.loads(_state(store, _sessions(store)["OLD-1"]))
        with store.read() as db:
            recorded = db.scalars(select(StudyRow.model_hash)).one()
    finally:
        store.dispose()
    rig = model_for_recorded_hash(ict_model, recorded).rig  # rig 1: recorded before rig 2
    assert rig.reach_version is None
    assert old["schema"] == "emogen.ga.engine/1"
    assert all("trial" in s and "attempt" not in s for s in old["selections"])
    assert {s["trial"] for s in old["selections"]} == {0, 1}  # a restart: two attempts
    config = GAConfig.model_validate(old["config"])
    replayed = Engine.replay(config, rig, old["seed"], old["selections"], stream=1)
    restored = Engine.from_json(old, rig)
    assert replayed.attempt == restored.attempt == old["trial"] == 1
    assert replayed.done and restored.done
    assert replayed.result.ids.tolist() == old["result"]["ids"]
    assert replayed.result.genes.tolist() == old["result"]["genes"]
    assert replayed.to_json() == restored.to_json()
    assert [s["attempt"] for s in restored.selections] == [s["trial"] for s in old["selections"]]
