"""The compiled model cache: parsed arrays stored as ``.npz``, keyed by the source content hash.

A small index per source folder maps each file's (name, size, mtime) fingerprint to the content
hash computed when the files were last parsed, so a warm load costs a few ``stat`` calls and one
uncompressed ``np.load``. Any change to a file changes its fingerprint and forces a re-parse;
a cache that cannot be read or written is ignored (logged), never fatal.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import IO

import numpy as np
import platformdirs

from emogen.model.io.ict import INDEX_FILE, ModelArrays
from emogen.model.io.obj import ObjTopology

log = logging.getLogger(__name__)
CACHE_FORMAT = 2  # 2: landmarks


def cache_root() -> Path:
    """Where compiled models live: ``$EMOGEN_CACHE_DIR`` or the user cache folder."""
    return Path(os.environ.get("EMOGEN_CACHE_DIR") or platformdirs.user_cache_dir("emogen"))


def folder_fingerprint(folder: Path) -> str:
    """Names, sizes and modification times of the model's source files (cheap to compute)."""
    entries = []
    for path in sorted(folder.iterdir()):
        if path.suffix.lower() == ".obj" or path.name == INDEX_FILE:
            st = path.stat()
            entries.append(f"{path.name}:{st.st_size}:{st.st_mtime_ns}")
    return hashlib.sha256("\n".join(entries).encode()).hexdigest()


def _index_path(folder: Path) -> Path:
    key = hashlib.sha256(str(folder.resolve()).encode()).hexdigest()[:16]
    return cache_root() / "compiled" / f"index-{key}.json"


def _data_path(source_hash: str) -> Path:
    return cache_root() / "compiled" / f"model-v{CACHE_FORMAT}-{source_hash[:32]}.npz"


def load_cached(folder: Path) -> ModelArrays | None:
    """The cached arrays for ``folder`` if its files are unchanged since they were compiled."""
    try:
        index = json.loads(_index_path(folder).read_text())
        if index.get("format") != CACHE_FORMAT or index.get("fingerprint") != folder_fingerprint(
            folder
        ):
            return None
        with np.load(_data_path(index["source_hash"]), allow_pickle=False) as z:
            topo = ObjTopology(
                polygons=z["polygons"],
                polygon_uvs=z["polygon_uvs"],
                uvs=z["uvs"],
                polygon_material=z["polygon_material"],
                materials=tuple(str(m) for m in z["materials"]),
            )
            return ModelArrays(
                name=str(z["name"]),
                neutral=z["neutral"],
                shape_names=tuple(str(s) for s in z["shape_names"]),
                deltas=z["deltas"],
                identity_names=tuple(str(s) for s in z["identity_names"]),
                identity_deltas=z["identity_deltas"],
                topology=topo,
                source_hash=str(z["source_hash"]),
                model_hash=str(z["model_hash"]),
                landmarks=z["landmarks"],
            )
    except (OSError, ValueError, KeyError, json.JSONDecodeError) as exc:
        if not isinstance(exc, FileNotFoundError):
            log.warning("ignoring unreadable model cache for %s: %s", folder, exc)
        return None


def _atomic_write(path: Path, write: Callable[[IO[bytes]], object]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name, suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            write(fh)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def store(folder: Path, arrays: ModelArrays) -> None:
    """Write the compiled arrays and the folder's index; failures are logged, not raised."""
    try:
        topo = arrays.topology
        _atomic_write(
            _data_path(arrays.source_hash),
            lambda fh: np.savez(
                fh,
                name=np.str_(arrays.name),
                neutral=arrays.neutral,
                shape_names=np.array(arrays.shape_names),
                deltas=arrays.deltas,
                identity_names=np.array(arrays.identity_names, dtype=str),
                identity_deltas=arrays.identity_deltas,
                polygons=topo.polygons,
                polygon_uvs=topo.polygon_uvs,
                uvs=topo.uvs,
                polygon_material=topo.polygon_material,
                materials=np.array(topo.materials),
                source_hash=np.str_(arrays.source_hash),
                model_hash=np.str_(arrays.model_hash),
                landmarks=arrays.landmarks,
            ),
        )
        index = {
            "format": CACHE_FORMAT,
            "folder": str(folder.resolve()),
            "fingerprint": folder_fingerprint(folder),
            "source_hash": arrays.source_hash,
        }
        _atomic_write(_index_path(folder), lambda fh: fh.write(json.dumps(index).encode()))
    except OSError as exc:
        log.warning("could not write the model cache under %s: %s", cache_root(), exc)
