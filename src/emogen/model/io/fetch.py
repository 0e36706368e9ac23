"""Download the ICT-FaceKit model files listed in EmoGen's manifest (`emogen model fetch`).

Every file is streamed to a temporary file next to its destination, checked against the
manifest's size and SHA-256, and only then moved into place with `os.replace`, so a failed or
interrupted download never leaves a partial file under the final name. Files already present
with the right checksum are skipped, which makes an interrupted fetch resumable. The manifest is read by :mod:`~emogen.model.io.manifest`, each file downloaded by
:mod:`~emogen.model.io.download`.

The files come from ``DEFAULT_BASE_URL`` (GitHub, pinned to the manifest's commit) unless a
mirror is given: the ``base_url`` argument wins over the ``EMOGEN_MODEL_URL`` environment
variable, which wins over the default. A mirror is a URL prefix (``{commit}`` is replaced by the
manifest's commit) or a local folder laid out like the repository.
"""

from __future__ import annotations

import logging
import os
import urllib.parse
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import platformdirs

from emogen.errors import ConfigError
from emogen.model.io.digest import file_sha256
from emogen.model.io.download import ENV_BASE_URL, download_file
from emogen.model.io.manifest import Manifest, ManifestFile, load_manifest

__all__ = [
    "DEFAULT_BASE_URL",
    "ENV_BASE_URL",
    "ENV_CACHE_DIR",
    "Manifest",
    "ManifestFile",
    "default_model_dir",
    "fetch_model",
    "load_manifest",
    "resolve_base_url",
]

DEFAULT_BASE_URL = "https://raw.githubusercontent.com/ICT-VGL/ICT-FaceKit/{commit}/"
ENV_CACHE_DIR = "EMOGEN_CACHE_DIR"
MODEL_SUBDIR = "FaceXModel"

logger = logging.getLogger(__name__)


def default_model_dir(commit: str | None = None) -> Path:
    """Where `fetch_model` installs the model when no destination is given.

    ``$EMOGEN_CACHE_DIR`` (or the user cache folder, e.g. ``~/.cache/emogen``) /
    ``ict-facekit`` / the first 8 characters of the commit (default: the packaged manifest's).
    """
    if commit is None:
        commit = load_manifest().commit
    root = os.environ.get(ENV_CACHE_DIR) or platformdirs.user_cache_dir("emogen")
    return Path(root) / "ict-facekit" / commit[:8]


def resolve_base_url(base_url: str | None, commit: str) -> str:
    """The URL prefix files are fetched from: argument > ``$EMOGEN_MODEL_URL`` > default.

    ``{commit}`` is replaced by ``commit``; a local folder becomes a ``file://`` URL.
    """
    chosen = base_url or os.environ.get(ENV_BASE_URL) or DEFAULT_BASE_URL
    chosen = chosen.replace("{commit}", commit)
    if "://" not in chosen:
        chosen = Path(chosen).expanduser().resolve().as_uri()
    return chosen if chosen.endswith("/") else chosen + "/"


def fetch_model(
    dest: Path | None = None,
    *,
    base_url: str | None = None,
    manifest: Manifest | Mapping[str, Any] | None = None,
    progress: bool = True,
    timeout: float = 60.0,
    retries: int = 3,
    retry_delay: float = 1.0,
) -> Path:
    """Download every manifest file into ``dest`` (default `default_model_dir`).

    Paths are kept relative to the repository root (``dest/FaceXModel/*.obj``, ``dest/LICENSE``).
    Files already present with the right SHA-256 are skipped. Transient network failures
    (connection errors, timeouts, HTTP 5xx/429) are retried ``retries`` times with exponential
    back-off starting at ``retry_delay`` seconds. ``progress`` shows a byte progress bar on stderr.

    Returns ``dest / "FaceXModel"``. Raises `ModelFileError` naming the file and URL when a file
    cannot be downloaded or does not match the manifest.
    """
    if not timeout > 0:
        raise ConfigError(f"timeout must be a positive number of seconds; got {timeout!r}")
    if isinstance(retries, bool) or not isinstance(retries, int) or retries < 0:
        raise ConfigError(f"retries must be a non-negative integer; got {retries!r}")
    if not retry_delay >= 0:
        raise ConfigError(f"retry_delay must be >= 0 seconds; got {retry_delay!r}")
    if manifest is None:
        manifest = load_manifest()
    elif not isinstance(manifest, Manifest):
        manifest = Manifest.from_mapping(manifest)
    dest = Path(dest) if dest is not None else default_model_dir(manifest.commit)
    base = resolve_base_url(base_url, manifest.commit)

    missing = [entry for entry in manifest.files if not _is_verified(dest, entry)]
    if missing:
        logger.info(
            "fetching %d of %d model files from %s", len(missing), len(manifest.files), base
        )
    with _progress_bar(progress, sum(e.size for e in missing)) as advance:
        for entry in missing:
            url = base + urllib.parse.quote(entry.path)
            download_file(
                url,
                entry,
                dest / entry.path,
                commit=manifest.commit,
                timeout=timeout,
                retries=retries,
                retry_delay=retry_delay,
                advance=advance,
            )
    return dest / MODEL_SUBDIR


def _is_verified(dest: Path, entry: ManifestFile) -> bool:
    target = dest / entry.path
    try:
        if not target.is_file() or target.stat().st_size != entry.size:
            return False
        return file_sha256(target) == entry.sha256
    except OSError:
        return False


@contextmanager
def _progress_bar(enabled: bool, total: int) -> Iterator[Callable[[int, str], None]]:
    """Yield ``advance(n_bytes, description)``; a rich byte progress bar when enabled."""
    if not enabled or total == 0:
        yield lambda n_bytes, description: None
        return
    from rich.console import Console
    from rich.progress import (
        BarColumn,
        DownloadColumn,
        Progress,
        TextColumn,
        TimeRemainingColumn,
        TransferSpeedColumn,
    )

    columns = (
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        DownloadColumn(),
        TransferSpeedColumn(),
        TimeRemainingColumn(),
    )
    with Progress(*columns, console=Console(stderr=True)) as bar:
        task = bar.add_task("ICT-FaceKit", total=total)

        def advance(n_bytes: int, description: str) -> None:
            bar.update(task, advance=n_bytes, description=description)

        yield advance
