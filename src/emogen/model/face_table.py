"""Tables of faces: one row per face, one column per shape or gene name.

A face table is a CSV or Parquet file whose columns are shape names (``jawOpen``,
``mouthSmile_L``, …; or ``w_jawOpen``, as simulation faces and study exports name them) or gene
names (``mouthSmile``: both shapes of the pair); shapes without a column are 0, and columns are
written in order (a later column overwrites an earlier one it shares shapes with). What else a table may hold depends on where it comes from:

* ``others="ignore"``: other columns (``run``, ``generation``, ``participant``, …) are kept for
  a ``query`` and otherwise ignored — the faces table of a simulation is one. Read with pandas
  (typed columns), CSV or Parquet by suffix.
* ``others="error"``: a CSV of weights only (plus ``label_columns``), read as written: an
  unknown column is an error naming it, and only an empty cell is missing (``NA`` is not a
  number). Errors give the file line.

One set of rules for every command that reads faces (``render --weights``, ``correct``,
``simulate --target-file``, ``--training``, analysis inputs):

* a column that is no shape or gene name is an error naming it and the closest known name when
  the table holds weights only — except EmoGen's own bookkeeping columns (``group``,
  ``participant``, ``emotion``, …) and corrective weights (``w_corr_…``, derived from the
  shapes and recomputed), which every reader passes over, so that every table EmoGen writes
  (an analysis report's ``prototypes.csv`` included) reads everywhere; in a table with bookkeeping columns (``others="ignore"``) a
  column that looks like a misspelt shape or gene (``jawOpn``) is still an error, never
  dropped quietly;
* a weight must be a finite number in [0, 1]; an empty cell is an error (or no weight, where
  ``blank="zero"``); a table without rows is an error.

Every error is a :class:`~emogen.errors.DataError` in one format,
``WHAT FILE: column 'NAME' row N (line L): PROBLEM``, where row 1 is the first row after the
header (``(line L)``, the line in a CSV file, where it is known), and values are shown as
written (``'1.7'``, ``1.7``), never as numpy reprs.
"""

from __future__ import annotations

import csv
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Literal

import numpy as np

from emogen.errors import ConfigError, DataError

if TYPE_CHECKING:
    import pandas as pd

    from emogen.model.rig import Rig

__all__ = ["FaceTable", "face_weights", "read_face_table", "read_table"]

PARQUET_SUFFIXES = (".parquet", ".pq")


@dataclass(frozen=True)
class FaceTable:
    """Faces read from a table.

    weights : (n_faces, n_shapes) float — full weight vectors, the rig's shape order.
    frame : the table as read (after ``query``), one row per face.
    columns : the shape- and gene-name columns, in table order.
    values : (n_faces, len(columns)) float — their cells, NaN where empty (``blank="zero"``).
    labels : per face, the last label column's text, stripped ("" when none).
    """

    weights: np.ndarray
    frame: pd.DataFrame
    columns: tuple[str, ...]
    values: np.ndarray
    labels: tuple[str, ...]


def read_table(path: str | Path, *, what: str = "face table") -> pd.DataFrame:
    """A Parquet (.parquet, .pq) or CSV (.csv) table, with pandas' typed columns."""
    import pandas as pd

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (*PARQUET_SUFFIXES, ".csv"):
        raise ConfigError(f"{what} {path}: expected a .parquet or .csv file; got '{suffix}'")
    try:
        return pd.read_parquet(path) if suffix != ".csv" else pd.read_csv(path)
    except FileNotFoundError:
        raise ConfigError(f"{what} {path} does not exist") from None
    except pd.errors.EmptyDataError:
        raise ConfigError(
            f"{what} {path} is empty: expected a header row of column names"
        ) from None
    except (OSError, ValueError) as exc:
        raise ConfigError(f"cannot read {what} {path}: {exc}") from None


def _read_text_csv(path: Path, what: str) -> tuple[pd.DataFrame, list[int]]:
    """A CSV as written (every cell a string, a short row padded with ""), and each row's line."""
    import pandas as pd

    try:
        with path.open(newline="", encoding="utf-8-sig") as fh:
            reader = csv.reader(fh)
            header = [h.strip() for h in next(reader, [])]
            rows, lines = [], []
            for row in reader:
                if not row:
                    continue  # a blank line, as csv.DictReader and pandas skip it
                if len(row) > len(header):
                    raise ConfigError(
                        f"{what} {path} line {reader.line_num}: {len(row)} values, "
                        f"but the header has {len(header)} columns"
                    )
                rows.append(row + [""] * (len(header) - len(row)))
                lines.append(reader.line_num)
    except FileNotFoundError:
        raise ConfigError(f"{what} {path} does not exist") from None
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise ConfigError(f"cannot read {what} {path} as CSV: {exc}") from None
    repeated = sorted({h for h in header if header.count(h) > 1})
    if repeated:
        raise ConfigError(f"{what} {path}: column(s) {repeated} appear more than once")
    return pd.DataFrame(rows, columns=header, dtype=object), lines


def read_face_table(
    path: str | Path,
    rig: Rig,
    *,
    what: str = "face table",
    query: str | None = None,
    others: Literal["ignore", "error"] = "ignore",
    label_columns: tuple[str, ...] = (),
    blank: Literal["error", "zero"] = "error",
    unit_range: bool = True,
) -> FaceTable:
    """The faces of a table (see the module docstring for ``others``).

    what : how errors name the file (``"--weights"``, ``"target_file"``). query : a pandas
    query selecting rows (``others="ignore"`` only). label_columns : column names (any case)
    holding a face's label, not weights. blank : an empty cell is an error, or leaves its
    shapes as the earlier columns wrote them (0 when none). unit_range : weights must be in
    [0, 1].
    """
    path = Path(path)
    lines: list[int] | None = None
    if others == "error":
        frame, lines = _read_text_csv(path, what)
    else:
        frame = read_table(path, what=what)
    if query:
        try:
            frame = frame.query(query)
        except Exception as exc:  # pandas raises many kinds for a bad expression
            raise ConfigError(f"query {query!r} on {path} failed: {exc}") from None
    if len(frame) == 0:
        raise DataError(
            f"{what} {path} has no rows{' matching ' + repr(query) if query else ''}: no faces "
            f"(expected a header row and one row per face)"
        )
    return face_weights(
        frame,
        rig,
        f"{what} {path}",
        others=others,
        label_columns=label_columns,
        blank=blank,
        unit_range=unit_range,
        lines=lines,
    )


def face_weights(
    frame: pd.DataFrame,
    rig: Rig,
    source: str = "table",
    *,
    others: Literal["ignore", "error"] = "ignore",
    label_columns: tuple[str, ...] = (),
    blank: Literal["error", "zero"] = "error",
    unit_range: bool = True,
    lines: list[int] | None = None,
) -> FaceTable:
    """Full weights (n_rows, n_shapes) from a table's shape- and gene-name columns.

    source : how errors name the table. lines : each row's line in the file, for errors.
    """
    shapes = {s: i for i, s in enumerate(rig.shape_names)}
    genes = {g.name: [shapes[s] for s in g.shapes] for g in rig.genes}
    labels = {c.lower() for c in label_columns}
    used, label_cols = [], []
    for c in frame.columns:
        name = _shape_name(str(c).strip(), shapes)
        if name in shapes or name in genes:
            used.append(c)
        elif name.lower() in labels:
            label_cols.append(c)
        else:
            _check_other_column(name, rig, source, others, label_columns)
    if not used and others == "ignore":
        raise DataError(
            f"{source}: no column is a shape or gene name of rig '{rig.name}' (e.g. "
            f"{', '.join(rig.shape_names[:3])}); columns are: {', '.join(map(str, frame.columns))}"
        )
    rows = _row_names(frame, lines)
    w = np.zeros((len(frame), len(rig.shape_names)))
    values = np.empty((len(frame), len(used)))
    for j, c in enumerate(used):
        name = _shape_name(str(c).strip(), shapes)
        v = _column_values(frame[c], f"{source}: column '{name}'", rows)
        empty = np.isnan(v)
        if empty.any() and blank == "error":
            row = int(np.flatnonzero(empty)[0])
            raise DataError(f"{source}: column '{name}' {rows[row]}: empty or missing weight")
        if unit_range:
            bad = np.flatnonzero(~empty & ((v < 0) | (v > 1)))
            if len(bad):
                raise DataError(
                    f"{source}: column '{name}' {rows[bad[0]]}: weight must be in [0, 1]; "
                    f"got {_cell_text(frame[c].iloc[bad[0]])}"
                )
        targets = genes[name] if name in genes else [shapes[name]]
        w[np.ix_(np.flatnonzero(~empty), np.asarray(targets, dtype=np.intp))] = v[~empty, None]
        values[:, j] = v
    return FaceTable(
        w,
        frame,
        tuple(_shape_name(str(c).strip(), shapes) for c in used),
        values,
        _labels(frame, label_cols),
    )


def _shape_name(name: str, shapes: dict[str, int]) -> str:
    """A column's shape name: ``w_<shape>`` (the weight columns of simulation faces and study
    exports) is the shape."""
    return name[2:] if name.startswith("w_") and name[2:] in shapes else name


def _cell_text(cell: object) -> str:
    """A cell as the user wrote it: text quoted, numbers plain (no ``np.float64(…)``)."""
    if isinstance(cell, str):
        return repr(cell)
    if isinstance(cell, np.generic):
        cell = cell.item()
    return repr(cell)


#: Columns EmoGen itself writes beside weights (simulation faces, study exports): never taken
#: for a misspelt shape name.
BOOKKEEPING = frozenset(
    {
        "run",
        "generation",
        "slot",
        "operator",
        "distance",
        "error",
        "rank",
        "run_seed",
        "seed",
        "study",
        "session_id",
        "participant_id",
        "trial",
        "attempt",
        "face_id",
        "role",
        "emotion",
        "identity",
        "label",
        "name",
        "group",
        "participant",
        "sample",
        "n_trials",
        "block_name",
        "repetition",
        "source",
    }
)


def derived_column(name: str) -> bool:
    """EmoGen's own columns beside weights (:data:`BOOKKEEPING`) and the corrective weights it
    writes (``w_corr_…``, ``w_collision_…``, rig 2's ``w_reach_…``: derived from the shapes,
    recomputed by every command that corrects):
    read past, never weights and never errors, in every face table."""
    return name in BOOKKEEPING or name.startswith(
        ("w_corr_", "corr_", "w_collision_", "collision_", "w_reach_", "reach_")
    )


def _check_other_column(
    name: str, rig: Rig, source: str, others: str, label_columns: tuple[str, ...]
) -> None:
    """A column that is no shape, gene or label: an error where the table holds weights only,
    and wherever it looks like a misspelt shape or gene name (``jawOpn``)."""
    import difflib

    known = [*rig.shape_names, *(g.name for g in rig.genes)]
    close = difflib.get_close_matches(name, known, n=1, cutoff=0.8)
    if not close:  # case and separator slips: 'JawOpen', 'jaw_open'
        squash = {re.sub(r"[^a-z0-9]", "", k.lower()): k for k in known}
        key = re.sub(r"[^a-z0-9]", "", name.lower())
        close = [squash[key]] if key in squash else []
    if derived_column(name) or (others == "ignore" and not close):
        return
    hint = f"did you mean '{close[0]}'? " if close else ""
    allowed = f" or {'/'.join(label_columns)}" if label_columns else ""
    raise DataError(
        f"{source}: unknown column '{name}': {hint}columns must be shape or gene names of rig "
        f"'{rig.name}'{allowed}" + ("" if close else f"; shapes are: {', '.join(rig.shape_names)}")
    )


def _row_names(frame: pd.DataFrame, lines: list[int] | None) -> list[str]:
    """How errors name each row: row 1 is the first row after the header (a query keeps the
    file's numbering); ``(line L)`` is its line in a CSV file, where known."""
    index = frame.index
    numbers = (
        [int(i) + 1 for i in index] if index.dtype.kind in "iu" else list(range(1, len(frame) + 1))
    )
    if lines is None:
        return [f"row {n}" for n in numbers]
    return [f"row {n} (line {line})" for n, line in zip(numbers, lines, strict=True)]


def _column_values(column: pd.Series, where: str, rows: list[str]) -> np.ndarray:
    """A column's weights as floats, NaN where the cell is empty; a non-number is an error."""
    if column.dtype.kind in "biuf":
        v = column.to_numpy(dtype=np.float64)
        bad = np.flatnonzero(np.isinf(v))
        if len(bad):
            raise DataError(f"{where} {rows[bad[0]]}: {float(v[bad[0]])} is not a finite number")
        return v
    v = np.full(len(column), np.nan)
    for i, cell in enumerate(column.tolist()):
        if cell is None or (isinstance(cell, float) and np.isnan(cell)):
            continue
        if isinstance(cell, str) and not cell.strip():
            continue
        try:
            v[i] = float(cell)
        except (TypeError, ValueError):
            raise DataError(f"{where} {rows[i]}: {_cell_text(cell)} is not a number") from None
        if not np.isfinite(v[i]):
            raise DataError(f"{where} {rows[i]}: {_cell_text(cell)} is not a finite number")
    return v


def _labels(frame: pd.DataFrame, label_cols: Sequence[object]) -> tuple[str, ...]:
    out = []
    for row in frame[label_cols].itertuples(index=False):
        texts = [x.strip() if isinstance(x, str) else "" for x in row]
        out.append(texts[-1] if texts else "")  # the last label column, as written
    return tuple(out)
