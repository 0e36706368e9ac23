"""A categorise block's face tables (``file``, ``others_fallback``): read and checked once when
the service starts (:meth:`emogen.tasks.categorise.task.CategoriseTask.prepare`)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from emogen.errors import ConfigError, DataError
from emogen.model.face_table import FaceTable, face_weights, read_table
from emogen.tasks.categorise.block import FILE_KEYS, CategoriseBlock


@dataclass(frozen=True)
class FileFaces:
    """A face table's rows: shape weights (n, n_shapes), and per row its identity (or None)
    and its label (the emotion it was made for, or None)."""

    path: Path
    weights: np.ndarray
    identities: list[str | None]
    labels: list[str | None]


def _column(frame: object, names: tuple[str, ...]) -> list[str | None] | None:
    cols = {str(c).lower(): c for c in getattr(frame, "columns", [])}
    for name in names:
        if name in cols:
            values = frame[cols[name]].tolist()  # type: ignore[index]
            return [
                None if v is None or str(v).strip() in ("", "nan") else str(v).strip()
                for v in values
            ]
    return None


def table_of(path: Path) -> Path:
    """A face table's file: ``path``, or a study export's ``final_faces`` table in a folder."""
    if not path.is_dir():
        return path
    for name in ("final_faces.parquet", "final_faces.csv"):
        if (path / name).is_file():
            return path / name
    raise ConfigError(
        f"{path} is a folder without final_faces.parquet or final_faces.csv: name a face table "
        "or a study export's folder"
    )


def face_table_at(path: Path, rig: Any, where: str) -> FaceTable:
    """The faces of a table file; a study export's table (``w_`` weight columns beside ``g_``
    gene columns, e.g. ``final_faces``) is read by its weights."""
    frame = read_table(path, what=where)
    if len(frame) == 0:
        raise DataError(f"{where} {path} has no rows: no faces (a header row, one row a face)")
    if any(str(c).startswith("w_") for c in frame.columns):
        frame = frame[[c for c in frame.columns if not str(c).startswith("g_")]]
    return face_weights(
        frame, rig, f"{where} {path}", label_columns=("label", "emotion", "identity")
    )


def read_file_faces(path: Path, ctx: Any, where: str) -> FileFaces:
    """A categorise block's face table (``file`` or ``others_fallback``), checked: its rows'
    identities must be the study's (errors name the block key, the file and the row)."""
    path = table_of(path)
    table = face_table_at(path, ctx.rig, where)
    n = len(table.weights)
    identities = _column(table.frame, ("identity",)) or [None] * n
    labels = _column(table.frame, ("label", "emotion")) or [None] * n
    known = set(ctx.config.all_identities())
    for row, name in enumerate(identities):
        if name is not None and name not in known:
            raise ConfigError(
                f"{where} {path} row {row + 1}: identity {name!r} is not one of the study's "
                f"identities ({', '.join(sorted(known))})"
            )
    if where.endswith("others_pool") and any(label is None for label in labels):
        raise ConfigError(
            f"{where} {path}: every row needs the emotion its face was made for (a 'label' or "
            "'emotion' column): others' faces are drawn balanced over the labels"
        )
    return FileFaces(path, table.weights, identities, labels)


def block_files(ctx: Any, k: int, block: CategoriseBlock) -> dict[str, FileFaces]:
    """Block ``k``'s face tables by key (``file``, ``others_fallback``), read and checked."""
    out: dict[str, FileFaces] = {}
    for key in FILE_KEYS:
        path = getattr(block, key)
        if path is not None:
            out[key] = read_file_faces(Path(path), ctx, f"blocks[{k + 1}].{key}")
    return out
