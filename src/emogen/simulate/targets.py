"""Faces from tables: simulation targets and training sets for the empirical metrics.

A face table is a Parquet or CSV file with one column per shape name (``jawOpen``,
``mouthSmile_L``, …) or gene name (``mouthSmile``: both shapes of the pair); other columns
(``run``, ``generation``, ``participant``, …) are ignored. The faces table of a simulation
written with all weights is one, so an evolved face can be the next simulation's target.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from emogen.config import SimulationConfig
from emogen.errors import ConfigError, DataError
from emogen.model.face_table import face_weights, read_face_table
from emogen.model.rig import Rig


def file_digest(path: Path) -> str:
    """sha256 of a file's bytes (what a sweep's config hash records for files it reads)."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def weights_from_table(table: pd.DataFrame, rig: Rig, source: str = "table") -> np.ndarray:
    """(n_rows, n_shapes) full weights from a table's shape- and gene-name columns."""
    return face_weights(table, rig, source).weights


def read_faces(path: Path, rig: Rig, *, query: str | None = None) -> np.ndarray:
    """Full weights of every face (row) of a table, optionally filtered by a pandas query."""
    return read_face_table(path, rig, query=query).weights


@dataclass(frozen=True)
class Target:
    """A simulation's target: weights (n_shapes,) and where they came from (for the record)."""

    weights: np.ndarray
    source: dict[str, Any]


def resolve_target(config: SimulationConfig, rig: Rig) -> Target:
    """The target face of a simulation config: named weights, or a row of a face table."""
    if config.target is not None:
        return Target(rig.weights_from_names(config.target), {"kind": "named"})
    path = config.target_file
    if path is None:  # the config's validator rules this out
        raise ConfigError("a simulation needs target or target_file")
    table = read_face_table(path, rig, what="target_file")  # the one face-table reader
    n = len(table.weights)
    row = config.target_row
    if row is None:
        if n != 1:
            raise ConfigError(
                f"target_file {path} has {n} rows: say which with target_row (0 to {n - 1}; "
                "0 is the first row after the header)"
            )
        row = 0
    if not 0 <= row < n:
        raise ConfigError(
            f"target_row must be in [0, {n - 1}] for {path} (0 is the first row after the "
            f"header); got {row}"
        )
    w = table.weights[row]
    if not np.any(w > 0):
        raise DataError(
            f"target_file {path}: row {row + 1} (target_row {row}): the target has no non-zero "
            "weight"
        )
    return Target(w, {"kind": "file", "file": str(path), "row": row, "sha256": file_digest(path)})
