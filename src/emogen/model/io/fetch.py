"""Download the ICT-FaceKit model files listed in EmoGen's manifest (`emogen model fetch`).

Every file is streamed to a temporary file next to its destination, checked against the
manifest's size and SHA-256, and only then moved into place with `os.replace`, so a failed or
interrupted download never leaves a partial file under the final name. Files already present
with the right checksum are skipped, which makes an interrupted fetch resumable.

The files come from ``DEFAULT_BASE_URL`` (GitHub, pinned to the manifest's commit) unless a
mirror is given: the ``base_url`` argument wins over the ``EMOGEN_MODEL_URL`` environment
variable, which wins over the default. A mirror is a URL prefix (``{commit}`` is replaced by the
manifest's commit) or a local folder laid out like the repository.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import re
import secrets
import time
import urllib.error
import urllib.parse
import urllib.request
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from functools import cache
from http.client import HTTPException
from importlib import resources
from pathlib import Path, PurePosixPath
from typing import IO, Any

import platformdirs

from emogen.errors import ConfigError, ModelFileError
from emogen.model.io.digest import file_sha256

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
ENV_BASE_URL = "EMOGEN_MODEL_URL"
ENV_CACHE_DIR = "EMOGEN_CACHE_DIR"
MODEL_SUBDIR = "FaceXModel"

_CHUNK_BYTES = 1 << 16
_RETRYABLE_HTTP = frozenset({408, 425, 429, 500, 502, 503, 504})
_SHA256_RE = re.compile(r"[0-9a-f]{64}")

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class ManifestFile:
    """One file of the model: its path relative to the repository root, size and SHA-256."""

    path: str
    sha256: str
    size: int

    def __post_init__(self) -> None:
        pure = PurePosixPath(self.path)
        if (
            not self.path
            or "\\" in self.path
            or pure.is_absolute()
            or any(part in ("", ".", "..") for part in self.path.split("/"))
        ):
            raise ModelFileError(
                f"manifest path must be a relative POSIX path inside the repository; "
                f"got {self.path!r}"
            )
        if not isinstance(self.sha256, str) or not _SHA256_RE.fullmatch(self.sha256):
            raise ModelFileError(
                f"manifest sha256 of {self.path!r} must be 64 lowercase hex digits; "
                f"got {self.sha256!r}"
            )
        if isinstance(self.size, bool) or not isinstance(self.size, int) or self.size < 0:
            raise ModelFileError(
                f"manifest size of {self.path!r} must be a non-negative integer; got {self.size!r}"
            )


@dataclass(frozen=True)
class Manifest:
    """The files of one ICT-FaceKit commit that EmoGen downloads."""

    repository: str
    commit: str
    files: tuple[ManifestFile, ...]

    @property
    def total_size(self) -> int:
        """Bytes in all files together."""
        return sum(entry.size for entry in self.files)

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any]) -> Manifest:
        """Build a manifest from its JSON form: ``{"repository", "commit", "files": [...]}``."""
        try:
            files = tuple(
                ManifestFile(path=f["path"], sha256=f["sha256"], size=f["size"])
                for f in data["files"]
            )
            manifest = cls(
                repository=str(data["repository"]), commit=str(data["commit"]), files=files
            )
        except (KeyError, TypeError) as err:
            raise ModelFileError(
                f"manifest must have repository, commit and files[path, sha256, size]; "
                f"missing or malformed: {err}"
            ) from err
        paths = [entry.path for entry in files]
        duplicates = sorted({p for p in paths if paths.count(p) > 1})
        if duplicates:
            raise ModelFileError(f"manifest lists files more than once: {duplicates}")
        return manifest


@cache
def load_manifest() -> Manifest:
    """The manifest shipped with EmoGen (``emogen/data/ict_manifest.json``)."""
    resource = resources.files("emogen").joinpath("data/ict_manifest.json")
    try:
        data = json.loads(resource.read_text(encoding="utf-8"))
    except (OSError, ValueError) as err:
        raise ModelFileError(f"cannot read the packaged model manifest {resource}: {err}") from err
    return Manifest.from_mapping(data)


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
            _fetch_file(
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


# --------------------------------------------------------------------------- internals


class _TransientError(Exception):
    """A failure worth retrying; ``connecting`` tells whether no response was received."""

    def __init__(self, reason: str, *, connecting: bool) -> None:
        super().__init__(reason)
        self.reason = reason
        self.connecting = connecting


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


def _fetch_file(
    url: str,
    entry: ManifestFile,
    target: Path,
    *,
    commit: str,
    timeout: float,
    retries: int,
    retry_delay: float,
    advance: Callable[[int, str], None],
) -> None:
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise ModelFileError(
            f"cannot create folder {target.parent} for {entry.path}: {err}"
        ) from err
    last: _TransientError | None = None
    for attempt in range(retries + 1):
        if attempt:
            delay = retry_delay * 2 ** (attempt - 1)
            logger.warning(
                "retrying %s in %.1f s (attempt %d of %d): %s",
                url,
                delay,
                attempt + 1,
                retries + 1,
                last.reason if last else "",
            )
            time.sleep(delay)
        received = 0

        def counted(n_bytes: int) -> None:
            nonlocal received
            received += n_bytes
            advance(n_bytes, entry.path)

        try:
            _download_once(url, entry, target, commit=commit, timeout=timeout, advance=counted)
            return
        except _TransientError as err:
            last = err
            advance(-received, entry.path)  # the retry starts again from byte 0
    if last is None:  # pragma: no cover - the loop runs at least once
        raise ModelFileError(f"no download attempt was made for {entry.path} from {url}")
    attempts = f"{retries + 1} attempt{'s' if retries else ''}"
    if last.connecting:
        raise ModelFileError(
            f"could not reach {url} to download {entry.path} ({last.reason}; {attempts}): "
            f"check your network or set {ENV_BASE_URL} to a mirror"
        )
    raise ModelFileError(
        f"download of {entry.path} from {url} was interrupted ({last.reason}; {attempts}): "
        f"run the fetch again to resume, or set {ENV_BASE_URL} to a mirror"
    )


def _download_once(
    url: str,
    entry: ManifestFile,
    target: Path,
    *,
    commit: str,
    timeout: float,
    advance: Callable[[int], None],
) -> None:
    """One attempt: stream ``url`` into a temporary file, verify it, move it to ``target``."""
    temp = target.with_name(f".{target.name}.{secrets.token_hex(4)}.part")
    try:
        # os.open with 0o666 honours the umask, unlike tempfile.mkstemp's fixed 0o600.
        fd = os.open(temp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0), 0o666)
    except OSError as err:
        raise ModelFileError(f"cannot write {entry.path} into {target.parent}: {err}") from err
    try:
        with os.fdopen(fd, "wb") as out:
            size, sha256 = _stream(url, entry, out, timeout=timeout, advance=advance)
        if size != entry.size:
            raise ModelFileError(
                f"{entry.path}: {url} sent {size} bytes, expected {entry.size} "
                f"(ICT-FaceKit commit {commit[:8]}); the download was discarded"
            )
        if sha256 != entry.sha256:
            raise ModelFileError(
                f"{entry.path}: checksum mismatch for {url}: expected sha256 {entry.sha256}, "
                f"got {sha256}; the download was discarded"
            )
        os.replace(temp, target)
    except OSError as err:
        raise ModelFileError(f"cannot write {entry.path} into {target.parent}: {err}") from err
    finally:
        temp.unlink(missing_ok=True)


def _stream(
    url: str,
    entry: ManifestFile,
    out: IO[bytes],
    *,
    timeout: float,
    advance: Callable[[int], None],
) -> tuple[int, str]:
    """Copy the body of ``url`` into ``out``; return (bytes received, their SHA-256)."""
    from emogen import __version__

    request = urllib.request.Request(url, headers={"User-Agent": f"emogen/{__version__}"})
    try:
        response = urllib.request.urlopen(request, timeout=timeout)
    except urllib.error.HTTPError as err:
        err.close()
        if err.code in _RETRYABLE_HTTP:
            raise _TransientError(f"HTTP {err.code} {err.reason}", connecting=False) from err
        raise ModelFileError(
            f"{entry.path}: {url} returned HTTP {err.code} {err.reason}; "
            f"check the mirror ({ENV_BASE_URL}) has ICT-FaceKit at this path"
        ) from err
    except urllib.error.URLError as err:
        if isinstance(err.reason, FileNotFoundError):
            raise ModelFileError(f"{entry.path}: {url} does not exist") from err
        raise _TransientError(str(err.reason), connecting=True) from err
    except (OSError, HTTPException) as err:
        raise _TransientError(str(err) or type(err).__name__, connecting=True) from err

    digest = hashlib.sha256()
    size = 0
    with response:
        while True:
            try:
                chunk = response.read(_CHUNK_BYTES)
            except (OSError, HTTPException) as err:
                raise _TransientError(str(err) or type(err).__name__, connecting=False) from err
            if not chunk:
                break
            size += len(chunk)
            if size > entry.size:
                raise ModelFileError(
                    f"{entry.path}: {url} sent more than the expected {entry.size} bytes; "
                    f"the download was discarded"
                )
            digest.update(chunk)
            out.write(chunk)
            advance(len(chunk))
    return size, digest.hexdigest()
