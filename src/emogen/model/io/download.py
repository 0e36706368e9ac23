"""Download one file of the manifest: stream it to a temporary file next to its destination,
check its size and SHA-256, and only then move it into place (`os.replace`); transient network
failures are retried with exponential back-off. :func:`emogen.model.io.fetch.fetch_model`
calls :func:`download_file` for every file still missing."""

from __future__ import annotations

import hashlib
import logging
import os
import secrets
import time
import urllib.error
import urllib.request
from collections.abc import Callable
from http.client import HTTPException
from pathlib import Path
from typing import IO

from emogen.errors import ModelFileError
from emogen.model.io.manifest import ManifestFile

__all__ = ["ENV_BASE_URL", "download_file"]

#: Environment variable naming a mirror (the download errors suggest it).
ENV_BASE_URL = "EMOGEN_MODEL_URL"

_CHUNK_BYTES = 1 << 16
_RETRYABLE_HTTP = frozenset({408, 425, 429, 500, 502, 503, 504})

logger = logging.getLogger(__name__)


class _TransientError(Exception):
    """A failure worth retrying; ``connecting`` tells whether no response was received."""

    def __init__(self, reason: str, *, connecting: bool) -> None:
        super().__init__(reason)
        self.reason = reason
        self.connecting = connecting


def download_file(
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
    """Download ``url`` into ``target`` (verified against ``entry``), retrying ``retries`` times.

    ``advance(n_bytes, description)`` reports progress (negative when a retry starts over).
    Raises `ModelFileError` naming the file and URL when it cannot be downloaded.
    """
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
