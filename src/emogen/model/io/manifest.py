"""The manifest of the ICT-FaceKit files EmoGen downloads: paths, sizes and SHA-256 digests
(``emogen/data/ict_manifest.json``), read and checked."""

from __future__ import annotations

import json
import re
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cache
from importlib import resources
from pathlib import PurePosixPath
from typing import Any

from emogen.errors import ModelFileError

__all__ = ["Manifest", "ManifestFile", "load_manifest"]

_SHA256_RE = re.compile(r"[0-9a-f]{64}")


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
