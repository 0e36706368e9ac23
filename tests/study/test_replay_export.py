"""``emogen replay`` from exported files: the export alone (Parquet or CSV + the config it
carries) regenerates every population, and a changed value in the files is found."""

from __future__ import annotations

import shutil
from pathlib import Path

import pandas as pd
import pytest
import typer
from typer.testing import CliRunner

from emogen.cli.study import replay_command
from emogen.study.export import export_tables, write_export
from emogen.study.replay_export import replay_exported
from emogen.study.sessions import StudyService
from emogen.study.storage import Store
from tests.export_helpers import as_schema5
from tests.study.test_export_replay import completed

RECORDED = Path(__file__).parents[1] / "data" / "study_stream1.sqlite"


@pytest.mark.parametrize("fmt", ["parquet", "csv"])
def test_exported_sessions_replay_exactly(
    service: StudyService, tmp_path: Path, ict_model, fmt: str
) -> None:
    completed(service, "X-1", restart=True)
    completed(service, "X-2")
    out = tmp_path / fmt
    write_export(export_tables(service.store), out, fmt)
    reports = replay_exported(out, ict_model.rig, ict_model.model_hash, model=ict_model)
    assert [r.session_id for r in reports] == [1, 2]
    assert all(r.ok for r in reports), [r.mismatches for r in reports]
    assert reports[0].populations == 7 and reports[0].faces == 70
    assert reports[1].populations == 6

    faces_path = out / f"faces.{fmt}"
    faces = pd.read_parquet(faces_path) if fmt == "parquet" else pd.read_csv(faces_path)
    column = next(c for c in faces.columns if c.startswith("w_"))
    faces.loc[13, column] += 1e-6
    if fmt == "parquet":
        faces.to_parquet(faces_path, index=False)
    else:
        faces.to_csv(faces_path, index=False)
    again = replay_exported(
        out, ict_model.rig, ict_model.model_hash, model=ict_model, session_ids=[1]
    )
    assert len(again) == 1 and not again[0].ok
    assert (
        again[0].mismatches == ["session 1 trial 1 attempt 1 generation 0, position 3: weights"]
        or "weights" in again[0].mismatches[0]
    )


def test_a_recorded_study_replays_from_its_export(tmp_path: Path, ict_model) -> None:
    copy = tmp_path / "recorded.sqlite"
    shutil.copyfile(RECORDED, copy)
    store = Store(f"sqlite:///{copy}")  # migrated to schema 2 on opening
    try:
        write_export(export_tables(store), tmp_path / "csv", "csv")
    finally:
        store.dispose()
    reports = replay_exported(
        tmp_path / "csv", ict_model.rig, ict_model.model_hash, model=ict_model
    )
    assert [(r.ok, r.populations) for r in reports] == [(True, 13), (True, 4)]


def test_cli_replays_an_export_folder(service: StudyService, tmp_path: Path, ict_dir: Path) -> None:
    completed(service, "C-1")
    write_export(export_tables(service.store), tmp_path / "out", "csv")
    app = typer.Typer()
    app.command("replay")(replay_command)
    app.command("other")(lambda: None)
    runner = CliRunner()
    args = ["replay", "--from-export", str(tmp_path / "out"), "--model", str(ict_dir)]
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    assert "session 1: 6 populations, 60 faces replayed: every face matches" in result.output
    # an export of schema 5 (no final_faces; ratings, responses under their old names)
    old = as_schema5(tmp_path / "out", tmp_path / "old")
    result = runner.invoke(app, ["replay", "--from-export", str(old), "--model", str(ict_dir)])
    assert result.exit_code == 0, result.output
    assert "session 1: 6 populations, 60 faces replayed: every face matches" in result.output
    result = runner.invoke(app, ["replay", "--from-export", str(tmp_path / "nothing")])
    assert result.exit_code == 2 and "no study.parquet or study.csv" in result.output
    result = runner.invoke(app, ["replay"])
    assert result.exit_code == 2 and "SESSION_ID" in result.output
