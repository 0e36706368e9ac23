"""What an export table is: its name, its columns and their types, and how its rows are made.

Each task declares its own tables (:attr:`emogen.tasks.protocol.Task.export_tables`, in its
package's ``export`` module; :func:`record_table` makes one straight from a record type); the
study's own tables are in :mod:`emogen.study.export_rows`; :mod:`emogen.study.export` writes
every one of them the same way. A table's rows come from a read's records
(:class:`emogen.study.export_rows.Records`: ``key``, ``stamp``, ``block_name``,
``face_values``, ``rows_of``, ``by_id``, ``by_trial``, ``by_session``, ``trials``,
``participants``). A column's type is declared with it (``name:kind``, the kinds of :mod:`emogen.columns`);
where :mod:`emogen.columns` has a rule for that name the two must agree (checked when the table
is defined), so Parquet, CSV and R's ``col_types.csv`` type it the same.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any, get_args

from sqlalchemy import Boolean, DateTime, Float, Integer

from emogen import columns as tidy
from emogen.tasks.records import as_utc

Row = dict[str, Any]
Column = tuple[str, tidy.Kind]

#: pandas dtypes of the kinds (for a declared column that :mod:`emogen.columns` has no rule for)
PANDAS_DTYPES = {"int": "Int64", "float": "float64", "str": "string", "bool": "boolean"}


def typed_columns(spec: str) -> tuple[Column, ...]:
    """``"study:str session_id:int …"`` as (name, kind) pairs."""
    kinds: dict[str, tidy.Kind] = {k: k for k in get_args(tidy.Kind)}
    out = []
    for item in spec.split():
        name, _, kind = item.partition(":")
        if kind not in kinds:
            raise ValueError(f"column {name!r}: kind must be one of {list(kinds)}; got {kind!r}")
        out.append((name, kinds[kind]))
    return tuple(out)


def record_columns(row: Any, skip: tuple[str, ...] = ("id", "trial_id")) -> tuple[Column, ...]:
    """A task record's columns as its row declares them (SQLAlchemy types as kinds), but
    ``skip``: a record's fields are named once, where the record is declared."""
    kinds: list[tuple[type, tidy.Kind]] = [
        (Boolean, "bool"),
        (Integer, "int"),
        (Float, "float"),
        (DateTime, "time"),
    ]
    out: list[Column] = []
    for column in row.__table__.columns:
        if column.name not in skip:
            found: tidy.Kind = next((k for t, k in kinds if isinstance(column.type, t)), "str")
            out.append((str(column.name), tidy.kind(column.name) or found))
    return tuple(out)


def record_values(record: Any, columns: tuple[Column, ...]) -> Row:
    """A record's values of ``columns`` (times as the exports write them; None: a record not
    made yet, every value missing)."""
    if record is None:
        return dict.fromkeys(name for name, _ in columns)
    out = {}
    for name, kind in columns:
        value = getattr(record, name)
        stamp = as_utc(value) if kind == "time" else None
        out[name] = stamp.isoformat() if stamp is not None else value
    return out


def iso(t: Any) -> str | None:
    """A stored time as ISO 8601 in UTC (None stays None)."""
    u = as_utc(t)
    return None if u is None else u.isoformat()


#: The columns that name a trial in every per-trial table.
TRIAL_KEY = typed_columns(
    "study:str session_id:int participant_id:str participant_source:str trial:int"
)


@dataclass(frozen=True)
class ExportTable:
    """One export table: ``name``, its fixed ``columns`` (then, with ``faces``, the study's
    ``g_<gene>`` and ``w_<weight>`` columns; then the record stamp), and ``rows`` (its rows from
    the records of a read). ``formerly``: its name in exports before schema 6 (readers of old
    exports look for that name too)."""

    name: str
    columns: tuple[Column, ...]
    #: the rows from a read's :class:`~emogen.study.export_rows.Records` (typed Any here: the
    #: records module defines its own tables with this class)
    rows: Callable[[Any], Iterator[Row]]
    faces: bool = False
    formerly: str | None = None

    def __post_init__(self) -> None:
        for name, kind in self.columns:
            rule = tidy.kind(name)
            if rule is not None and rule != kind:
                raise ValueError(
                    f"export table {self.name!r}: column {name!r} is declared {kind} but "
                    f"emogen.columns types it {rule}"
                )

    @property
    def column_names(self) -> list[str]:
        return [name for name, _ in self.columns]

    @property
    def dtypes(self) -> dict[str, str]:
        """pandas dtypes of the declared columns without a rule in :mod:`emogen.columns`."""
        return {
            n: PANDAS_DTYPES[k]
            for n, k in self.columns
            if tidy.kind(n) is None and k in PANDAS_DTYPES
        }


def record_table(row: Any) -> ExportTable:
    """A task's record type as an export table of its own: one row per record, named by its
    table, keyed by the trial it belongs to (:data:`TRIAL_KEY` and ``block``), its columns and
    types those its row declares (a field is named once: where the record is declared)."""
    columns = record_columns(row)

    def rows(rec: Any) -> Iterator[Row]:
        for record in rec.rows_of(row):
            t = rec.by_trial[record.trial_id]
            yield {
                **rec.key(t),
                "block": t.block,
                **record_values(record, columns),
                **rec.trial_stamp(t),
            }

    name = str(row.__table__.name)
    return ExportTable(name, TRIAL_KEY + typed_columns("block:int") + columns, rows)
