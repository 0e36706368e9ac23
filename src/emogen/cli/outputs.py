"""Output folders of every command that writes one (``--out FOLDER``), written all or nothing.

A command writes into a new hidden sibling folder (``.NAME.partial-PID-XXXX``) and only when it has
finished is that folder renamed to ``--out``: an interrupted or failed run leaves the earlier
output as it was (or no folder), never a mix of two runs. A folder that exists and is not empty
is refused unless ``--force``; with it, the old folder is replaced only once the new one is
complete. ``emogen sweep`` is the exception: its folder is resumable by design (cells are
skipped when already there), so it writes in place.

An interrupted run cleans up after itself: SIGTERM and SIGHUP (a closed terminal, a batch
system's time limit, ``kill``) end it the way Ctrl-C does, removing its partial folder; one
killed outright (SIGKILL, a power cut) leaves it, and the next run into the same folder removes
every partial folder whose process is gone (they may hold participant data).
"""

from __future__ import annotations

import os
import re
import shutil
import signal
import tempfile
import threading
import uuid
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated

import typer

from emogen.errors import ConfigError
from emogen.leftovers import remove_orphans

__all__ = ["ForceOpt", "check_out_folder", "moved", "output_folder"]

ForceOpt = Annotated[
    bool,
    typer.Option("--force", help="Replace an existing, non-empty --out folder (once complete)."),
]


def check_out_folder(out: Path, *, force: bool, option: str = "--out") -> None:
    """Refuse a file where a folder is wanted, and a non-empty folder without ``--force``."""
    if out.exists() and not out.is_dir():
        raise ConfigError(f"{option} {out} is a file; give a folder (a new or empty one)")
    if out.is_dir() and not force:
        entries = sorted(p.name for p in out.iterdir())
        if entries:
            raise ConfigError(
                f"{option} {out} is not empty ({len(entries)} entries, e.g. {entries[0]!r}): "
                "give a new folder, or --force to replace it"
            )


def remove_stale_partials(parent: Path, name: str) -> list[Path]:
    """Remove ``.NAME.partial-PID-*`` folders in ``parent`` whose process is gone."""
    pattern = re.compile(rf"\.{re.escape(name)}\.partial-(\d+)-")
    return remove_orphans(parent, f".{name}.partial-*", pattern)


class Terminated(SystemExit):
    """SIGTERM or SIGHUP, raised where the program is so that its clean-ups run."""


@contextmanager
def _signals_raise() -> Iterator[None]:
    """SIGTERM and SIGHUP raise :class:`Terminated` in the main thread while the block runs
    (elsewhere, or in another thread, nothing changes)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def stop(signum: int, _frame: object) -> None:
        raise Terminated(128 + signum)

    before = {sig: signal.signal(sig, stop) for sig in (signal.SIGTERM, signal.SIGHUP)}
    try:
        yield
    finally:
        for sig, handler in before.items():
            signal.signal(sig, handler)


@contextmanager
def output_folder(out: Path, *, force: bool, option: str = "--out") -> Iterator[Path]:
    """A temporary sibling folder to write into; renamed to ``out`` when the block succeeds,
    removed when it fails (``out`` is then untouched)."""
    out = Path(out)
    check_out_folder(out, force=force, option=option)
    parent = out.absolute().parent
    parent.mkdir(parents=True, exist_ok=True)
    remove_stale_partials(parent, out.name)
    with _signals_raise():
        tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.partial-{os.getpid()}-", dir=parent))
        umask = os.umask(0)
        os.umask(umask)
        tmp.chmod(0o777 & ~umask)  # mkdtemp makes 0700; a plain mkdir would follow the umask
        try:
            yield tmp
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
    old = parent / f".{out.name}.old-{uuid.uuid4().hex[:8]}"
    replaced = out.exists()
    if replaced:
        os.rename(out, old)
    try:
        os.rename(tmp, out)
    except OSError:
        if replaced:
            os.rename(old, out)
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    if replaced:
        shutil.rmtree(old, ignore_errors=True)


def moved(paths: Iterable[Path], tmp: Path, out: Path) -> list[Path]:
    """Where files written under ``tmp`` are once it has been renamed to ``out``."""
    tmp = Path(tmp)
    return [Path(out) / Path(p).relative_to(tmp) for p in paths]
