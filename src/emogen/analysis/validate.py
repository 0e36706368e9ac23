"""Checks on what :mod:`emogen.analysis.data` reads, before anything is computed from it.

An export edited by hand, converted by another tool or cut short must not be analysed quietly:
every table must have rows, key columns whole numbers, labels present, weights finite numbers
in [0, 1] and errors finite. Each failure is one :class:`~emogen.errors.DataError` in the face
tables' format: ``TABLE: column 'NAME' row N: PROBLEM`` (row 1 = the first row after the header).
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
import pandas as pd

from emogen.errors import DataError

__all__ = ["check_labels", "check_nonempty", "check_numbers", "check_study", "check_whole"]

#: Whole-number key columns of a study export's tables.
STUDY_KEYS = {
    "trials": ("session_id", "trial"),
    "faces": ("session_id", "trial", "attempt", "generation", "face_id"),
    "selections": ("session_id", "trial", "attempt", "generation", "face_id"),
}
STUDY_LABELS = {"trials": ("participant_id", "emotion", "status"), "selections": ("role",)}


def _shown(value: object) -> str:
    if isinstance(value, np.generic):
        value = value.item()
    return repr(value)


def _numbers(frame: pd.DataFrame, column: str, where: str) -> np.ndarray:
    """A column as floats; a cell that is not a number is an error naming it."""
    values = pd.to_numeric(frame[column], errors="coerce").to_numpy(dtype=np.float64)
    given = frame[column].notna().to_numpy()
    bad = np.flatnonzero(np.isnan(values) & given)
    if len(bad):
        raise DataError(
            f"{where}: column '{column}' row {bad[0] + 1}: "
            f"{_shown(frame[column].iloc[bad[0]])} is not a number"
        )
    return values


def check_nonempty(frame: pd.DataFrame, where: str, what: str) -> None:
    if len(frame) == 0:
        raise DataError(f"{where} has no rows: {what}")


def check_whole(
    frame: pd.DataFrame, columns: Iterable[str], where: str, *, allow_empty: bool = False
) -> None:
    """Key columns: present in every row (unless ``allow_empty``), whole numbers."""
    for c in columns:
        v = _numbers(frame, c, where)
        empty = np.isnan(v)
        bad = np.flatnonzero((empty & (not allow_empty)) | (~empty & (v != np.round(v))))
        if len(bad):
            cell = frame[c].iloc[bad[0]]
            problem = "empty" if pd.isna(cell) else f"{_shown(cell)} is not a whole number"
            raise DataError(f"{where}: column '{c}' row {bad[0] + 1}: {problem}")


def check_labels(frame: pd.DataFrame, columns: Iterable[str], where: str) -> None:
    for c in columns:
        if c not in frame.columns:
            continue
        bad = np.flatnonzero(frame[c].isna().to_numpy())
        if len(bad):
            raise DataError(f"{where}: column '{c}' row {bad[0] + 1}: empty")


def check_numbers(
    frame: pd.DataFrame,
    columns: Iterable[str],
    where: str,
    *,
    low: float,
    high: float,
    what: str,
    allow_empty: bool = False,
) -> None:
    """Finite numbers in [low, high] (empty cells allowed only with ``allow_empty``)."""
    for c in columns:
        v = _numbers(frame, c, where)
        empty = np.isnan(v)
        slack = 1e-9 * max(1.0, high - low)  # rounding of a distance computed in float
        inside = (v >= low - slack) & (v <= high + slack)
        bad = np.flatnonzero((empty & (not allow_empty)) | (~empty & ~inside))
        if len(bad):
            cell = frame[c].iloc[bad[0]]
            problem = (
                f"empty or missing {what}"
                if pd.isna(cell)
                else f"{what} must be in [{low:g}, {high:g}]; got {_shown(cell)}"
            )
            raise DataError(f"{where}: column '{c}' row {bad[0] + 1}: {problem}")


def check_study(
    folder: object, tables: dict[str, pd.DataFrame], other_trials: bool = False
) -> None:
    """The trials, faces and selections tables of a study export (columns already present);
    ``other_trials``: the study has trials of other tasks (categorise), so no GA trial is
    needed."""
    if not other_trials:
        check_nonempty(
            tables["trials"],
            f"{folder}/trials",
            "no trials to analyse (export again once participants have done trials)",
        )
    for name, keys in STUDY_KEYS.items():
        check_whole(tables[name], keys, f"{folder}/{name}")
    for name, labels in STUDY_LABELS.items():
        check_labels(tables[name], labels, f"{folder}/{name}")
    faces = tables["faces"]
    weights = [c for c in faces.columns if str(c).startswith("w_")]
    check_numbers(faces, weights, f"{folder}/faces", low=0.0, high=1.0, what="weight")


def check_simulation(
    folder: object, table: pd.DataFrame, faces: pd.DataFrame | None, weights: list[str]
) -> None:
    """A simulation's per-generation table and (when recorded) its faces table."""
    where = f"{folder}/simulation"
    for frame, name, needed in (
        (table, "simulation", ("run", "generation", "elite_error", "n_selected")),
        (faces, "faces", ("run", "generation", "error", "rank")),
    ):
        missing = [c for c in needed if frame is not None and c not in frame.columns]
        if missing:
            raise DataError(f"{folder}/{name}: missing columns {missing} (see docs/ga.md)")
    check_nonempty(table, where, "no runs to analyse")
    check_whole(table, ("run", "generation"), where)
    check_numbers(table, ("elite_error",), where, low=0.0, high=2.0, what="cosine distance")
    if faces is None:
        return
    where = f"{folder}/faces"
    check_whole(faces, ("run", "generation"), where)
    check_whole(faces, ("rank",), where, allow_empty=True)  # NA: not selected
    check_numbers(faces, ("error",), where, low=0.0, high=2.0, what="cosine distance")
    check_numbers(faces, weights, where, low=0.0, high=1.0, what="weight")
