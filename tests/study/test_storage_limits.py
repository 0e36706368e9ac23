"""The study database at the edges of a launch (issue #39): a full disk at start is said as
the documented message (not SQLite's "disk I/O error"), and a read-only copy — an archive —
exports without a write (opened read-only, not migrated)."""

from __future__ import annotations

import hashlib
import sqlite3
from pathlib import Path
from typing import Any

import pytest
from sqlalchemy.exc import OperationalError
from typer.testing import CliRunner

from emogen.cli.app import app
from emogen.errors import ResourceError
from emogen.study import storage
from emogen.study.config import study_from_dict
from emogen.study.storage import Store
from tests.study.conftest import SMALL_STUDY
from tests.study.drive import run_to_end, service_caller, study_service


def test_a_full_disk_at_start_is_named(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    def io_error(engine: Any, revision: str = "head") -> None:
        raise OperationalError("BEGIN", {}, sqlite3.OperationalError("disk I/O error"))

    monkeypatch.setattr("emogen.study.migrations.upgrade", io_error)
    monkeypatch.setattr(storage, "MIN_FREE_BYTES", 1 << 62)  # this disk: as good as full
    with pytest.raises(ResourceError) as err:
        Store(f"sqlite:///{tmp_path / 'full.sqlite'}")
    message = str(err.value)
    assert (
        "cannot save anything in" in message and "the disk of the study database is full" in message
    )
    assert "disk I/O error" not in message


def test_a_read_only_copy_exports_without_a_write(tmp_path: Path, ict_model: Any) -> None:
    url = f"sqlite:///{tmp_path / 'live.sqlite'}"
    store = Store(url)
    service = study_service(study_from_dict(SMALL_STUDY), store, ict_model)
    token, _ = service.create_session("P-1")
    run_to_end(service.state(token), service_caller(service, token))
    store.dispose()
    archive = tmp_path / "archive.sqlite"  # a copy as archives keep it: one file, no WAL
    with sqlite3.connect(tmp_path / "live.sqlite") as live, sqlite3.connect(archive) as copy:
        live.backup(copy)
    with sqlite3.connect(archive) as copy:
        copy.execute("PRAGMA journal_mode=DELETE")
    before = hashlib.sha256(archive.read_bytes()).hexdigest()
    out = tmp_path / "out"
    result = CliRunner().invoke(
        app,
        [
            "study",
            "export",
            "--database-url",
            f"sqlite:///{archive}",
            "--out",
            str(out),
            "--format",
            "csv",
        ],
    )
    assert result.exit_code == 0, result.output
    assert "P-1" in (out / "sessions.csv").read_text()
    # nothing written: not the journal mode (a write of the header), not a migration
    assert hashlib.sha256(archive.read_bytes()).hexdigest() == before
    assert not (tmp_path / "archive.sqlite-wal").exists()
    with sqlite3.connect(archive) as copy:
        assert copy.execute("PRAGMA journal_mode").fetchone()[0] == "delete"
