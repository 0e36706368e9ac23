"""A corrected study recorded with rig 1 (before the reach shapes, tests/data/study_rig1.sqlite)
replays exactly with today's package: the replay finds rig 1 by the recorded model hash, and
corrects the replayed faces with rig 1's correctives (no reach shapes)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from sqlalchemy import select

from emogen.model.load import model_for_recorded_hash
from emogen.study.export import export_tables, write_export
from emogen.study.replay import replay_session
from emogen.study.replay_export import replay_exported
from emogen.study.storage import Store
from emogen.study.tables import SessionRow, StudyRow

RECORDED = Path(__file__).parents[1] / "data" / "study_rig1.sqlite"


def _open(tmp_path: Path) -> Store:
    copy = tmp_path / "recorded.sqlite"
    shutil.copyfile(RECORDED, copy)
    return Store(f"sqlite:///{copy}")


def _study(store: Store) -> StudyRow:
    with store.read() as db:
        return db.scalars(select(StudyRow)).one()


def test_a_study_recorded_with_rig_1_replays_exactly(tmp_path: Path, ict_model) -> None:
    assert ict_model.rig.reach_version == 1  # today's default rig is rig 2
    store = _open(tmp_path)
    try:
        study = _study(store)
        assert study.model_hash != ict_model.model_hash
        weights = json.loads(study.weight_names)
        assert not any(w.startswith("reach_") for w in weights)
        old = model_for_recorded_hash(ict_model, study.model_hash)
        assert old.model_hash == study.model_hash and old.rig.reach_version is None
        with store.read() as db:
            ids = list(db.scalars(select(SessionRow.id)))
        assert len(ids) == 2
        for sid in ids:
            report = replay_session(
                store, sid, ict_model.rig, ict_model.model_hash, model=ict_model
            )
            assert report.mismatches == [], report.mismatches
            assert report.populations == 8 and report.faces == 80
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


def test_the_study_server_continues_a_rig_1_study_with_rig_1(tmp_path: Path, ict_model) -> None:
    """`emogen serve` of the recorded config: the app loads rig 1 (its hash, its GLB's
    correctives), so the study registers as the same study instead of refusing to start."""
    from emogen.study.config import StudyConfig
    from emogen.web import create_app

    copy = tmp_path / "recorded.sqlite"
    shutil.copyfile(RECORDED, copy)
    store = Store(f"sqlite:///{copy}")
    try:
        study = _study(store)
        config = StudyConfig.model_validate(json.loads(study.config_json))
    finally:
        store.dispose()
    app = create_app(config, f"sqlite:///{copy}", model=ict_model)
    try:
        assert app.state.model.model_hash == study.model_hash
        assert app.state.model.rig.reach_version is None
        assert app.state.service.ctx.study_id == study.id
    finally:
        app.state.store.dispose()
