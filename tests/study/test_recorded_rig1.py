"""Corrected studies recorded with rig 1 (before the reach shapes, tests/data/study_rig1.sqlite)
and with rig 2 (reach shapes version 1, study_rig2.sqlite) replay exactly with today's package
(rig 3): the replay finds the recorded rig by the recorded model hash, and corrects the replayed
faces with that rig's correctives."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from sqlalchemy import select

from emogen.model.load import model_for_recorded_hash
from emogen.study.export import export_tables, write_export
from emogen.study.replay import replay_session
from emogen.study.replay_export import replay_exported
from emogen.study.storage import Store
from emogen.study.tables import SessionRow, StudyRow

DATA = Path(__file__).parents[1] / "data"
RECORDED = DATA / "study_rig1.sqlite"
#: (recorded file, its rig's reach version, its participants' populations and faces)
RIGS = [("study_rig1.sqlite", None, 8, 80), ("study_rig2.sqlite", 1, 12, 120)]


def _open(tmp_path: Path, recorded: Path = RECORDED) -> Store:
    copy = tmp_path / "recorded.sqlite"
    shutil.copyfile(recorded, copy)
    return Store(f"sqlite:///{copy}")


def _study(store: Store) -> StudyRow:
    with store.read() as db:
        return db.scalars(select(StudyRow)).one()


@pytest.mark.parametrize(("recorded", "reach", "populations", "faces"), RIGS)
def test_a_study_recorded_with_an_older_rig_replays_exactly(
    tmp_path: Path, ict_model, recorded: str, reach: int | None, populations: int, faces: int
) -> None:
    assert ict_model.rig.reach_version == 2  # today's default rig is rig 3
    store = _open(tmp_path, DATA / recorded)
    try:
        study = _study(store)
        assert study.model_hash != ict_model.model_hash
        weights = json.loads(study.weight_names)
        assert not any(w.startswith(("reach_smileOpen", "reach_lipTightener")) for w in weights)
        old = model_for_recorded_hash(ict_model, study.model_hash)
        assert old.model_hash == study.model_hash and old.rig.reach_version == reach
        with store.read() as db:
            ids = list(db.scalars(select(SessionRow.id)))
        assert len(ids) == 2
        for sid in ids:
            report = replay_session(
                store, sid, ict_model.rig, ict_model.model_hash, model=ict_model
            )
            assert report.mismatches == [], report.mismatches
            assert report.populations == populations and report.faces == faces
            assert report.model_hash_matches and report.ok
        out = tmp_path / "export"
        write_export(export_tables(store), out)
        reports = replay_exported(out, ict_model.rig, ict_model.model_hash, model=ict_model)
        assert len(reports) == 2 and all(r.ok and not r.mismatches for r in reports)
    finally:
        store.dispose()


def test_an_unknown_recorded_hash_keeps_the_model_and_replay_says_it_differs(
    tmp_path: Path, ict_model
) -> None:
    assert model_for_recorded_hash(ict_model, "0" * 64) is ict_model
    store = _open(tmp_path)
    try:
        with store.write() as db:
            db.scalars(select(StudyRow)).one().model_hash = "0" * 64
        with store.read() as db:
            sid = db.scalars(select(SessionRow.id)).first()
        report = replay_session(store, sid, ict_model.rig, ict_model.model_hash, model=ict_model)
        assert not report.model_hash_matches and not report.ok
    finally:
        store.dispose()


@pytest.mark.parametrize(("recorded", "reach", "populations", "faces"), RIGS)
def test_the_study_server_continues_a_study_with_its_recorded_rig(
    tmp_path: Path, ict_model, recorded: str, reach: int | None, populations: int, faces: int
) -> None:
    """`emogen serve` of the recorded config: the app loads the recorded rig (its hash, its
    GLB's correctives), so the study registers as the same study instead of refusing to start."""
    from emogen.study.config import StudyConfig
    from emogen.web import create_app

    copy = tmp_path / "recorded.sqlite"
    shutil.copyfile(DATA / recorded, copy)
    store = Store(f"sqlite:///{copy}")
    try:
        study = _study(store)
        config = StudyConfig.model_validate(json.loads(study.config_json))
    finally:
        store.dispose()
    app = create_app(config, f"sqlite:///{copy}", model=ict_model)
    try:
        assert app.state.model.model_hash == study.model_hash
        assert app.state.model.rig.reach_version == reach
        assert app.state.service.ctx.study_id == study.id
    finally:
        app.state.store.dispose()
