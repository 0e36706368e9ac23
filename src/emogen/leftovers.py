"""Folders named after the process writing them (``…-PID-…``), removed once it is gone.

Exports and dashboard downloads write participant data into temporary folders that carry the
writing process's id; a process killed outright (SIGKILL, a power cut) cannot remove its own,
so the next run removes every such folder whose process no longer exists.
"""

from __future__ import annotations

import os
import re
import shutil
from pathlib import Path


def process_alive(pid: int) -> bool:
    """Whether a process with this id exists (another user's counts)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def remove_orphans(parent: Path, glob: str, pattern: re.Pattern[str]) -> list[Path]:
    """Remove the folders in ``parent`` matching ``glob`` whose name's process id (``pattern``'s
    first group) is gone; returns those removed."""
    removed = []
    for entry in Path(parent).glob(glob):
        found = pattern.match(entry.name)
        if found and entry.is_dir() and not process_alive(int(found.group(1))):
            shutil.rmtree(entry, ignore_errors=True)
            removed.append(entry)
    return removed
