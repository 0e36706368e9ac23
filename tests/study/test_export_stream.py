"""Exports written a few sessions at a time hold what one table of all the rows holds, and
incremental exports (``--since``) appended together hold each completed session exactly once."""

from __future__ import annotations

import json
from datetime import UTC, datetime, timedelta
from pathlib import Path

import pandas as pd
import pytest
from sqlalchemy import update
from typer.testing import CliRunner

from emogen import columns as tidy
from emogen.cli.study import study_app
from emogen.errors import ConfigError
from emogen.study import export_stream
from emogen.study.export import TABLES, export_tables, write_export
from emogen.study.export_stream import SETTLE, export_study, parse_since
from emogen.study.replay_export import replay_exported
from emogen.study.sessions import StudyService
from emogen.study.tables import SessionRow
from tests.study.drive import do, new_key, run_to_end, service_caller
from tests.study.test_export_replay import completed

runner = CliRunner()
PER_SESSION = (
    "sessions",
    "trials",
    "faces",
    "selections",
    "restarts",
    "evolve_ratings",
    "final_faces",
)


def read(path: Path) -> pd.DataFrame:
    return pd.read_parquet(path) if path.suffix == ".parquet" else tidy.read_csv(path)


def reference(tables: dict[str, pd.DataFrame], name: str, fmt: str, tmp: Path) -> pd.DataFrame:
    """One DataFrame of all the rows (the in-memory export), written by the in-memory writer."""
    folder = tmp / "ref"
    if not folder.is_dir():
        write_export(tables, folder, fmt)
    return read(folder / f"{name}.{fmt}")


@pytest.mark.parametrize("fmt", ["parquet", "csv"])
def test_chunked_export_holds_what_one_table_holds(
    service: StudyService, tmp_path: Path, ict_model, fmt: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    completed(service, "S-1", restart=True)
    completed(service, "S-2")
    token, _ = service.create_session("S-3")  # in the middle: NA in completed_at, ga_stream …
    state = do(service, "begin", token, new_key())
    run_to_end(state, service_caller(service, token), stop=lambda s: s["progress"]["trial"] == 1)
    service.create_session("S-4")  # never began: no trials, no faces
    monkeypatch.setattr(export_stream, "CHUNK_ROWS", 25)  # a chunk per session or so
    chunks = export_stream.session_chunks(service.store, [service.ctx.study_id], None, None)
    assert len(chunks) >= 4 and sorted(s for c in chunks for s in c) == [1, 2, 3, 4]
    result = export_study(service.store, tmp_path / "out", fmt)
    whole = export_tables(service.store)
    assert [p.name for p in result.paths] == [f"{t}.{fmt}" for t in TABLES]
    for name in TABLES:
        got = read(tmp_path / "out" / f"{name}.{fmt}")
        want = reference(whole, name, fmt, tmp_path)
        assert result.rows[name] == len(whole[name]), name
        assert list(got.columns) == list(want.columns), name
        pd.testing.assert_frame_equal(got, want, obj=name)  # types too
        if fmt == "parquet":  # the same provenance in the file's schema metadata
            prov = tidy.provenance(tmp_path / "out" / f"{name}.{fmt}")
            assert prov == tidy.provenance(tmp_path / "ref" / f"{name}.{fmt}"), name
            assert prov["table"] == name and prov["studies"][0]["model_hash"]
    assert not list((tmp_path / "out").glob("emogen-export-*"))  # the spill is removed
    reports = replay_exported(
        tmp_path / "out", ict_model.rig, ict_model.model_hash, model=ict_model
    )
    assert all(r.ok for r in reports) and len(reports) >= 2


def test_incremental_exports_appended_hold_each_completed_session_once(
    service: StudyService, tmp_path: Path
) -> None:
    for p in ("I-1", "I-2", "I-3"):
        completed(service, p)
    token, _ = service.create_session("I-4")  # not completed: never in an incremental export
    do(service, "begin", token, new_key())
    t0 = datetime(2026, 5, 1, 12, 0, tzinfo=UTC)
    with service.store.write() as db:  # completion times under the test's control
        for sid, minutes in ((1, 0), (2, 10), (3, 20)):
            db.execute(
                update(SessionRow)
                .where(SessionRow.id == sid)
                .values(completed_at=t0 + timedelta(minutes=minutes))
            )
    first = export_study(
        service.store,
        tmp_path / "a",
        "parquet",
        since=t0 - timedelta(days=1),
        now=t0 + timedelta(minutes=10) + SETTLE,
    )
    assert first.until == t0 + timedelta(minutes=10)
    manifest = json.loads((tmp_path / "a" / "export.json").read_text())
    assert manifest["until"] == first.until.isoformat() and manifest["sessions"] == 1
    second = export_study(
        service.store, tmp_path / "b", "parquet", since=first.until, now=t0 + timedelta(hours=1)
    )
    assert sorted(pd.read_parquet(tmp_path / "a" / "sessions.parquet").session_id) == [1]
    # completed exactly at the first cut-off: in the second export, not the first
    assert sorted(pd.read_parquet(tmp_path / "b" / "sessions.parquet").session_id) == [2, 3]
    assert second.since == first.until
    whole = export_tables(service.store)
    for name in PER_SESSION:
        appended = pd.concat(
            [pd.read_parquet(tmp_path / d / f"{name}.parquet") for d in ("a", "b")],
            ignore_index=True,
        )
        want = whole[name][whole[name].participant_id != "I-4"]
        assert len(appended) == len(want), name
        assert not appended.drop(columns=["completed_at"], errors="ignore").duplicated().any()
        key = [
            c
            for c in ("session_id", "trial", "attempt", "generation", "position", "rank")
            if c in want.columns
        ]
        pd.testing.assert_frame_equal(
            appended.sort_values(key).reset_index(drop=True),
            want.sort_values(key).reset_index(drop=True),
            check_dtype=False,
            obj=name,
        )
    # the per-study tables are whole in every export
    assert len(pd.read_parquet(tmp_path / "b" / "study.parquet")) == 1


def test_since_is_checked_and_named(service: StudyService, tmp_path: Path) -> None:
    assert parse_since("2026-05-01 12:00") == datetime(2026, 5, 1, 12, 0, tzinfo=UTC)
    assert parse_since("2026-05-01T14:00:00+02:00") == datetime(2026, 5, 1, 12, 0, tzinfo=UTC)
    with pytest.raises(ConfigError, match=r"--since.*'yesterday'"):
        parse_since("yesterday")
    url = service.store.url
    result = runner.invoke(
        study_app, ["export", "--database-url", url, "-o", str(tmp_path), "--since", "yesterday"]
    )
    assert result.exit_code == 2 and "'yesterday'" in result.output
    result = runner.invoke(
        study_app, ["export", "--database-url", url, "-o", str(tmp_path), "--table", "face"]
    )
    assert result.exit_code == 2 and "'face'" in result.output
    completed(service, "C-1")
    result = runner.invoke(
        study_app,
        [
            "export",
            "--database-url",
            url,
            "-o",
            str(tmp_path / "i"),
            "--format",
            "csv",
            "--since",
            "2000-01-01",
            "--table",
            "sessions",
        ],
    )
    assert result.exit_code == 0, result.output
    # completed less than SETTLE ago: not yet in an incremental export
    assert "sessions.csv (0 rows)" in result.output and "--since 20" in result.output
    written = sorted(p.name for p in (tmp_path / "i").iterdir())
    assert written == ["col_types.csv", "export.json", "sessions.csv"]
