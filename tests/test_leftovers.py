"""No participant data left lying around (issue 33): an export interrupted by SIGTERM or SIGHUP
removes its partial folder, one killed outright has it removed by the next run, and a dashboard
download is private (0700/0600) and removed by the next server when its server was killed."""

from __future__ import annotations

import asyncio
import os
import signal
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

import pytest

from emogen.cli.outputs import output_folder
from tests.study.conftest import SMALL_STUDY

INTERRUPTED = """
import os, signal, sys, time
from pathlib import Path
from emogen.cli.outputs import output_folder
with output_folder(Path(sys.argv[1]), force=False) as tmp:
    (tmp / "sessions.csv").write_text("participant_id\\nP001\\n")
    os.kill(os.getpid(), getattr(signal, sys.argv[2]))
    time.sleep(30)
"""


def dead_pid() -> int:
    """The id of a process that has ended (and been reaped)."""
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


@pytest.mark.parametrize("sig", ["SIGTERM", "SIGHUP"])
def test_an_export_stopped_by_a_signal_removes_its_partial_folder(tmp_path: Path, sig: str) -> None:
    out = tmp_path / "export"
    done = subprocess.run(
        [sys.executable, "-c", INTERRUPTED, str(out), sig],
        timeout=60,
        capture_output=True,
        text=True,
    )
    assert done.returncode == 128 + getattr(signal, sig), done.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == []  # no .export.partial-* left


def test_the_next_export_removes_partial_folders_of_killed_runs(tmp_path: Path) -> None:
    killed = tmp_path / f".export.partial-{dead_pid()}-abcd1234"
    running = tmp_path / f".export.partial-{os.getpid()}-efgh5678"  # a run still going
    for folder in (killed, running):
        folder.mkdir()
        (folder / "sessions.csv").write_text("participant_id\nP001\n")
    with output_folder(tmp_path / "export", force=False) as tmp:
        (tmp / "sessions.csv").write_text("participant_id\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["export", running.name])


def test_a_download_is_private_while_it_exists(tmp_path: Path, ict_model: Any) -> None:
    from emogen.study.config import study_from_dict
    from emogen.web import create_app
    from emogen.web.exports import export_table_file

    app = create_app(
        study_from_dict(SMALL_STUDY), f"sqlite:///{tmp_path / 's.sqlite'}", model=ict_model
    )
    app.state.store.dispose()
    lock = asyncio.Lock()
    answer = asyncio.run(export_table_file(lock, app.state.store.url, "small", "sessions", None))
    path = Path(answer.path)
    temp = Path(tempfile.gettempdir()).resolve()
    try:
        assert path.stat().st_mode & 0o777 == 0o600
        folder = path.parent
        while folder.resolve() != temp:
            assert folder.stat().st_mode & 0o777 == 0o700, folder
            folder = folder.parent
    finally:
        assert answer.background is not None
        asyncio.run(answer.background())  # what runs once the file is sent
    assert not path.exists()


def test_a_killed_servers_downloads_are_removed_when_the_next_starts(
    tmp_path: Path, ict_model: Any
) -> None:
    from emogen.study.config import study_from_dict
    from emogen.web import create_app

    left = Path(tempfile.mkdtemp(prefix=f"emogen-download-{dead_pid()}-"))
    (left / "sessions.csv").write_text("participant_id\nP001\n")
    mine = Path(tempfile.mkdtemp(prefix=f"emogen-download-{os.getpid()}-"))  # a live server's
    try:
        app = create_app(
            study_from_dict(SMALL_STUDY), f"sqlite:///{tmp_path / 's.sqlite'}", model=ict_model
        )
        app.state.store.dispose()
        assert not left.exists() and mine.exists()
    finally:
        for folder in (left, mine):
            if folder.exists():
                for f in folder.iterdir():
                    f.unlink()
                folder.rmdir()
