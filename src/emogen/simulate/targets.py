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
from emogen.errors import ConfigError
from emogen.model.rig import Rig


def read_table(path: Path) -> pd.DataFrame:
    """A Parquet (.parquet, .pq) or CSV (.csv) table."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".parquet", ".pq", ".csv"):
        raise ConfigError(f"face table {path}: expected a .parquet or .csv file; got '{suffix}'")
    try:
        return pd.read_parquet(path) if suffix != ".csv" else pd.read_csv(path)
    except FileNotFoundError:
        raise ConfigError(f"face table {path} does not exist") from None
    except (OSError, ValueError) as exc:
        raise ConfigError(f"cannot read face table {path}: {exc}") from None


def file_digest(path: Path) -> str:
    """sha256 of a file's bytes (what a sweep's config hash records for files it reads)."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def weights_from_table(table: pd.DataFrame, rig: Rig, source: str = "table") -> np.ndarray:
    """(n_rows, n_shapes) full weights from a table's shape- and gene-name columns."""
    shapes = {s: i for i, s in enumerate(rig.shape_names)}
    genes = {g.name: [shapes[s] for s in g.shapes] for g in rig.genes}
    used = [c for c in table.columns if c in shapes or c in genes]
    if not used:
        raise ConfigError(
            f"{source}: no column is a shape or gene name of rig '{rig.name}' (e.g. "
            f"{', '.join(rig.shape_names[:3])}); columns are: {', '.join(map(str, table.columns))}"
        )
    w = np.zeros((len(table), len(rig.shape_names)))
    for c in used:
        values = pd.to_numeric(table[c], errors="coerce").to_numpy(dtype=np.float64)
        if not np.all(np.isfinite(values)):
            raise ConfigError(f"{source}: column '{c}' has missing or non-numeric values")
        w[:, genes[c] if c in genes else [shapes[c]]] = values[:, None]
    return w


def read_faces(path: Path, rig: Rig, *, query: str | None = None) -> np.ndarray:
    """Full weights of every face (row) of a table, optionally filtered by a pandas query."""
    table = read_table(path)
    if query:
        try:
            table = table.query(query)
        except Exception as exc:  # pandas raises many kinds for a bad expression
            raise ConfigError(f"query {query!r} on {path} failed: {exc}") from None
    if len(table) == 0:
        raise ConfigError(
            f"face table {path} has no rows{' matching ' + repr(query) if query else ''}"
        )
    return weights_from_table(table, rig, str(path))


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
    table = read_table(path)
    row = config.target_row
    if row is None:
        if len(table) != 1:
            raise ConfigError(
                f"target_file {path} has {len(table)} rows: say which with target_row "
                f"(0 to {len(table) - 1})"
            )
        row = 0
    if not 0 <= row < len(table):
        raise ConfigError(f"target_row must be in [0, {len(table) - 1}] for {path}; got {row}")
    w = weights_from_table(table.iloc[[row]], rig, f"target_file {path}")[0]
    bad = [rig.shape_names[i] for i in np.flatnonzero((w < 0) | (w > 1))]
    if bad:
        raise ConfigError(f"target_file {path} row {row}: weights of {bad} must be in [0, 1]")
    if not np.any(w > 0):
        raise ConfigError(f"target_file {path} row {row}: the target has no non-zero weight")
    return Target(w, {"kind": "file", "file": str(path), "row": row, "sha256": file_digest(path)})
