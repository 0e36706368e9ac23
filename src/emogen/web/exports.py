"""Dashboard downloads: an export table written by a separate, lower-priority process.

``emogen study export`` (CSV or Parquet, any table) runs as a child process at idle priority (Linux ``SCHED_IDLE``: it gets
a core only when no participant request wants one; elsewhere ``nice`` 19) into a temporary
folder and the file is then streamed to the researcher: the export's memory is bounded (a few
sessions at a time) and never the server's, its CPU time goes to participants' steps first, and it holds no
lock of this process (the GIL included), so participants' requests are not stalled while it
runs. One export at a time per worker process; the database URL reaches the child through its
environment, never its command line.

The tables hold participant data, so they are private while they exist and are removed on
every way out: the child writes with umask 077 (files 0600, folders 0700) inside a private
folder ``emogen-download-PID-XXXX`` (0700) of the temporary folder; the folder is removed once
the file is sent, when the export fails or the request is cancelled (the child is then killed),
and the child dies with the server process (``SIGTERM`` on Linux). A server killed outright
leaves its folder: the next server to start removes every such folder whose process is gone
(:func:`remove_stale_downloads`).
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import re
import shutil
import sys
import tempfile
from pathlib import Path

from starlette.background import BackgroundTask
from starlette.responses import FileResponse

from emogen.leftovers import remove_orphans
from emogen.study.engines import DATABASE_ENV
from emogen.study.errors import StudyError

#: The child: idle priority (or the lowest nice), then ``python -m emogen`` with the given
#: arguments.
_CHILD = (
    "import os, runpy, signal, sys\n"
    "os.umask(0o077)\n"
    "if sys.platform == 'linux':\n"
    "    import ctypes\n"
    "    ctypes.CDLL(None).prctl(1, int(signal.SIGTERM))  # dies with the server\n"
    "    if os.getppid() != int(sys.argv.pop(1)):\n"
    "        sys.exit(1)\n"
    "else:\n"
    "    sys.argv.pop(1)\n"
    "try:\n"
    "    os.sched_setscheduler(0, os.SCHED_IDLE, os.sched_param(0))\n"
    "except (AttributeError, OSError):\n"
    "    os.nice(19)\n"
    "sys.argv = ['emogen', *sys.argv[1:]]\n"
    "runpy.run_module('emogen', run_name='__main__')\n"
)


class ExportFailed(StudyError):
    status = 503


PREFIX = "emogen-download-"
_STALE = re.compile(rf"{PREFIX}(\d+)-")


def remove_stale_downloads(folder: Path | None = None) -> list[Path]:
    """Remove download folders (``emogen-download-PID-*``) whose server process is gone."""
    return remove_orphans(Path(folder or tempfile.gettempdir()), f"{PREFIX}*", _STALE)


#: Download formats and their media types.
MEDIA_TYPES = {"csv": "text/csv", "parquet": "application/vnd.apache.parquet"}


async def export_table_file(
    lock: asyncio.Lock,
    database_url: str,
    study: str,
    table: str,
    since: str | None,
    fmt: str = "csv",
) -> FileResponse:
    """``table`` of ``study`` as a CSV or Parquet download (``since``: an incremental export's
    start)."""
    folder = Path(tempfile.mkdtemp(prefix=f"{PREFIX}{os.getpid()}-"))  # 0700
    out = folder / "export"
    args = [
        str(os.getpid()),
        "study",
        "export",
        "--format",
        fmt,
        "--table",
        table,
        "--study",
        study,
        "--out",
        str(out),
    ]
    if since is not None:
        args += ["--since", since]
    env = {**os.environ, DATABASE_ENV: database_url}
    child = None
    try:
        async with lock:
            child = await asyncio.create_subprocess_exec(
                sys.executable,
                "-c",
                _CHILD,
                *args,
                env=env,
                stdout=asyncio.subprocess.DEVNULL,
                stderr=asyncio.subprocess.PIPE,
            )
            _, err = await child.communicate()
        if child.returncode != 0:
            lines = err.decode(errors="replace").strip().splitlines() or ["no message"]
            raise ExportFailed(f"the export of {table} failed: {lines[-1]}")
    except BaseException:
        if child is not None and child.returncode is None:  # cancelled: the child goes too
            with contextlib.suppress(ProcessLookupError):
                child.kill()
            await asyncio.shield(child.wait())
        shutil.rmtree(folder, ignore_errors=True)
        raise
    return FileResponse(
        out / f"{table}.{fmt}",
        media_type=MEDIA_TYPES[fmt],
        filename=f"{table}.{fmt}",
        background=BackgroundTask(shutil.rmtree, folder, ignore_errors=True),
    )
