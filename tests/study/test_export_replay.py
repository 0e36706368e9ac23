"""Export (tidy tables, stamps) and replay, through the library and the CLI, on both backends."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pandas as pd
import typer
from sqlalchemy import select
from typer.testing import CliRunner

from emogen import __version__
from emogen.cli.study import replay_command, study_app
from emogen.study.export import STAMPS, TABLES, export_tables, write_export
from emogen.study.replay import replay_session
from emogen.study.sessions import StudyService
from emogen.study.tables import SCHEMA_VERSION
from emogen.tasks.evolve.tables import FaceRow
from tests.study.drive import do, new_key, run_to_end, service_caller, step_args

runner = CliRunner()


def completed(service: StudyService, participant: str, restart: bool = False) -> str:
    token, _ = service.create_session(participant)
    state = do(service, "begin", token, new_key())
    if restart:
        state = do(service, "restart", token, new_key(), **step_args(state))
    run_to_end(state, service_caller(service, token))
    return token


def test_export_holds_every_generation_and_selection(service: StudyService, tmp_path: Path) -> None:
    completed(service, "E-1", restart=True)
    token, _ = service.create_session("E-2")  # stopped in the middle
    state = do(service, "begin", token, new_key())
    run_to_end(state, service_caller(service, token), stop=lambda s: s["view"]["generation"] == 1)
    tables = export_tables(service.store)
    assert set(tables) == set(TABLES)
    for name, df in tables.items():
        for col in STAMPS:
            assert col in df.columns, (name, col)
        assert (df["schema_version"] == SCHEMA_VERSION).all()
        assert (df["package_version"] == __version__).all()
        assert (df["model_hash"] == service.ctx.model_hash).all()
        assert (df["study_config_hash"] == service.ctx.config.config_hash()).all()
    faces, sel = tables["faces"], tables["selections"]
    # E-1: trial 0 has attempt 0 gen 0 (restarted) + attempt 1 gens 0..2; trial 1 gens 0..2
    e1 = faces[faces.participant_id == "E-1"]
    gens = e1.groupby(["trial", "attempt"])["generation"].unique().apply(sorted).to_dict()
    assert gens == {(0, 0): [0], (0, 1): [0, 1, 2], (1, 0): [0, 1, 2]}
    assert (e1.groupby(["trial", "attempt", "generation"]).size() == 10).all()
    assert [c for c in faces.columns if c.startswith("w_")][:2] == ["w_browDown_L", "w_browDown_R"]
    # the shapes, then the corrective weights (correct = true)
    assert [c for c in faces.columns if c.startswith("w_")] == [
        f"w_{n}" for n in service.ctx.weight_names
    ]
    assert len(service.ctx.weight_names) > 57
    assert len([c for c in faces.columns if c.startswith("g_")]) == 30
    # every selection: one elite + 2 others per answered generation
    e1s = sel[sel.participant_id == "E-1"]
    assert len(e1s[e1s.role == "elite"]) == 6 and len(e1s) == 18
    assert (e1s.client_response_ms == 1234.5).all()
    assert len(tables["restarts"]) == 1 and len(tables["evolve_ratings"]) == 2
    e2 = sel[sel.participant_id == "E-2"]
    assert sorted(e2[e2.role == "elite"].generation) == [0]
    # shown weights in the export are exactly the stored ones
    with service.store.read() as db:
        first = db.scalars(select(FaceRow).order_by(FaceRow.id)).first()
    row = faces.iloc[0]
    assert [row[c] for c in faces.columns if c.startswith("w_")] == json.loads(first.weights)
    # both formats round-trip
    for fmt in ("parquet", "csv"):
        paths = write_export(tables, tmp_path / fmt, fmt)
        assert sorted(p.name for p in paths) == sorted(f"{t}.{fmt}" for t in TABLES)
        back = (
            pd.read_parquet(tmp_path / fmt / "faces.parquet")
            if fmt == "parquet"
            else pd.read_csv(tmp_path / fmt / "faces.csv")
        )
        assert len(back) == len(faces)


def test_replay_matches_and_detects_tampering(service: StudyService, ict_model) -> None:
    completed(service, "R-1", restart=True)
    report = replay_session(service.store, 1, ict_model.rig, ict_model.model_hash, model=ict_model)
    assert report.ok, report.mismatches
    assert report.populations == 7 and report.faces == 70
    with service.store.write() as db:
        face = db.scalars(select(FaceRow).where(FaceRow.position == 3).order_by(FaceRow.id)).all()[
            4
        ]
        w = json.loads(face.weights)
        w[0] += 1e-9
        face.weights = json.dumps(w)
    report = replay_session(service.store, 1, ict_model.rig, ict_model.model_hash, model=ict_model)
    assert not report.ok and len(report.mismatches) == 1
    assert "position 3: weights" in report.mismatches[0]
    assert not replay_session(
        service.store, 1, ict_model.rig, "other-hash", model=ict_model
    ).model_hash_matches


def test_cli_status_export_replay(service: StudyService, tmp_path: Path, ict_dir: Path) -> None:
    completed(service, "C-1")
    url = service.store.url
    result = runner.invoke(study_app, ["status", "--database-url", url, "--sessions"])
    assert result.exit_code == 0, result.output
    assert "study small" in result.output and "1 sessions (1 done)" in result.output
    assert "C-1" in result.output
    result = runner.invoke(study_app, ["status", "--database-url", url, "--json"])
    assert json.loads(result.output)["studies"][0]["steps"]["select"] == 6
    out = tmp_path / "export"
    result = runner.invoke(
        study_app, ["export", "--database-url", url, "--format", "csv", "--out", str(out)]
    )
    assert result.exit_code == 0, result.output
    assert (out / "selections.csv").is_file() and "faces.csv (60 rows)" in result.output
    result = runner.invoke(
        study_app, ["export", "--database-url", url, "--study", "nope", "-o", str(tmp_path / "n")]
    )
    assert result.exit_code == 2 and "no study named 'nope'" in result.output

    app = typer.Typer()
    app.command("replay")(replay_command)
    app.command("other")(lambda: None)  # keep replay a sub-command
    result = runner.invoke(app, ["replay", "1", "--database-url", url, "--model", str(ict_dir)])
    assert result.exit_code == 0, result.output
    assert "6 populations, 60 faces replayed: every face matches" in result.output
    result = runner.invoke(app, ["replay", "99", "--database-url", url, "--model", str(ict_dir)])
    assert result.exit_code == 2 and "no session with id 99" in result.output


def test_migrations_are_idempotent_and_match_the_models(db_url: str) -> None:
    from alembic.autogenerate import compare_metadata
    from alembic.runtime.migration import MigrationContext

    from emogen.study.migrations import current_revision
    from emogen.study.storage import Store
    from emogen.study.tables import Base, task_tables

    store = Store(db_url)
    store.migrate()  # a second upgrade does nothing
    assert current_revision(store.engine) == "0005"
    # the migrations make the study's tables and the built-in tasks' (a task of a lab's own, or
    # a test's toy task, brings tables the store creates: they are not the migrations' to make)
    study_tables = {"studies", "sessions", "trials", "steps", "researcher_failures"}
    built_in = {t.name for t in task_tables()} | study_tables

    def ours(obj: Any, name: str | None, kind: str, reflected: bool, other: Any) -> bool:
        return kind != "table" or name in built_in

    with store.engine.connect() as conn:
        context = MigrationContext.configure(conn, opts={"include_object": ours})
        diff = compare_metadata(context, Base.metadata)
    assert diff == []
    if not store.is_sqlite:
        store.dispose()
        return
    with store.engine.connect() as conn:
        assert conn.exec_driver_sql("PRAGMA journal_mode").scalar() == "wal"
        assert conn.exec_driver_sql("PRAGMA foreign_keys").scalar() == 1
        assert conn.exec_driver_sql("PRAGMA synchronous").scalar() == 2  # FULL
    store.dispose()


def test_head_is_alembics_head_and_a_current_database_opens_without_alembic(
    tmp_path: Path,
) -> None:
    from alembic.script import ScriptDirectory

    from emogen.study.migrations import HEAD, alembic_config

    assert ScriptDirectory.from_config(alembic_config()).get_current_head() == HEAD
    url = f"sqlite:///{tmp_path / 'study.sqlite'}"
    code = (
        "import sys; from emogen.study.storage import Store; Store(sys.argv[1]).dispose(); "
        "print(any(m.split('.')[0] == 'alembic' for m in sys.modules))"
    )
    run = [sys.executable, "-c", code, url]
    new = subprocess.run(run, capture_output=True, text=True, check=True)
    assert new.stdout.strip() == "True"  # a new database is migrated by Alembic
    again = subprocess.run(run, capture_output=True, text=True, check=True)
    assert again.stdout.strip() == "False"  # at HEAD: opened without it


def test_serve_command_reports_a_bad_config(tmp_path: Path) -> None:
    from emogen.cli.serve import serve_command

    app = typer.Typer()
    app.command("serve")(serve_command)
    app.command("other")(lambda: None)
    bad = tmp_path / "study.toml"
    bad.write_text("name = 'x'\nrepetitions = 0\n")
    result = runner.invoke(app, ["serve", str(bad), "--port", "1"])
    assert result.exit_code == 2
    assert "'repetitions' must be >= 1" in result.output
    result = runner.invoke(app, ["serve", "--help"])
    assert result.exit_code == 0 and "demo study" in result.output


def test_export_records_every_identity_to_render_it_again(
    db_url: str, ict_model, tmp_path: Path
) -> None:  # type: ignore[no-untyped-def]
    """The identities table (presets and the study's own) reads back as the config's identities,
    from Parquet and CSV; sessions of such a study replay exactly."""
    from emogen.appearance.identities import Identity
    from emogen.appearance.params import GENERATOR_VERSION
    from emogen.study.config import study_from_dict
    from emogen.study.export import identities_from_table
    from emogen.study.storage import Store
    from tests.study.conftest import SMALL_STUDY

    config = study_from_dict(
        {
            **SMALL_STUDY,
            "name": "faces",
            "emotions": ["happy"],
            "correct": False,
            "identities": ["male-dark", "lab_face", "lab_coeffs"],
            "identity": {
                "lab_face": {"shape": "female", "skin_tone": 3.5, "hair": "none", "seed": 9},
                "lab_coeffs": {"shape": [0.75, -0.5], "brow_colour": "#403020"},
            },
        }
    )
    store = Store(db_url)
    try:
        service = StudyService(
            config,
            store,
            ict_model.rig,
            model_name=ict_model.name,
            model_hash=ict_model.model_hash,
            model=ict_model,
        )
        completed(service, "I-1")
        tables = export_tables(store)
        ids = tables["identities"]
        assert list(ids.identity) == ["male-dark", "lab_face", "lab_coeffs"]
        assert (ids.appearance_generator == GENERATOR_VERSION).all()
        assert list(ids["shape"][:2]) == ["male", "female"] and pd.isna(ids["shape"].iloc[2])
        assert set(tables["trials"].identity) == set(ids.identity)  # joins on (study, identity)
        assert tables["trials"].collision_solver.isna().all()  # the study corrects no faces
        expected = {("faces", n): i for n, i in config.study_identities().items()}
        assert expected[("faces", "lab_coeffs")] == Identity(
            shape=(0.75, -0.5), appearance=config.identity["lab_coeffs"].appearance
        )
        assert identities_from_table(ids) == expected
        for fmt in ("parquet", "csv"):
            write_export(tables, tmp_path / fmt, fmt)
            path = tmp_path / fmt / f"identities.{fmt}"
            back = pd.read_parquet(path) if fmt == "parquet" else pd.read_csv(path)
            assert identities_from_table(back) == expected, fmt
        report = replay_session(store, 1, ict_model.rig, ict_model.model_hash)
        assert report.ok and report.populations == 9, report.mismatches
    finally:
        store.dispose()
