"""Export tables of the tasks' own records: one table per record type a task exports
(:attr:`emogen.tasks.protocol.Task.exported`), named by its table, its columns and their types
those the task declared on its row, each row keyed by the session, participant, block and trial
it belongs to (``session_id``, ``participant_id``, ``block``, ``trial``: the trial's position,
unique within its session).

A record's own ``id`` is its row in the database (unique in the table); every id a task keeps
within a trial (a face id) joins on (``session_id``, ``trial``) first.
"""

from __future__ import annotations

from typing import Any

import pandas as pd
from sqlalchemy import Boolean, DateTime, Float, Integer, select
from sqlalchemy.orm import Session

from emogen import columns as tidy
from emogen.study.tables import SessionRow, TrialRow, core_table
from emogen.tasks.registry import TASKS

#: The keys every task record's row carries, first.
KEYS = ("session_id", "participant_id", "block", "trial")


def task_export_tables() -> dict[str, Any]:
    """The record types the registered tasks export, by table name."""
    return {core_table(row).name: row for task in TASKS.values() for row in task.exported}


def _dtype(column: Any) -> str:
    kind = column.type
    if isinstance(kind, Boolean):
        return "boolean"
    if isinstance(kind, Integer):
        return "Int64"
    if isinstance(kind, Float):
        return "float64"
    if isinstance(kind, DateTime):
        return "datetime64[us, UTC]"
    return "string"


def _columns(row: Any) -> list[Any]:
    return [c for c in core_table(row).columns if c.name != "trial_id"]


def task_rows(db: Session, row: Any, session_ids: list[int]) -> list[dict[str, Any]]:
    """The records of type ``row`` of these sessions, keyed (:data:`KEYS`), in session, trial
    and record order."""
    cols = _columns(row)
    query = (
        select(SessionRow.id, SessionRow.participant_id, TrialRow.block, TrialRow.position, *cols)
        .join(TrialRow, TrialRow.id == core_table(row).c.trial_id)
        .join(SessionRow, SessionRow.id == TrialRow.session_id)
        .where(SessionRow.id.in_(session_ids))
        .order_by(SessionRow.id, TrialRow.position, core_table(row).c.id)
    )
    names = [*KEYS, *(c.name for c in cols)]
    return [dict(zip(names, values, strict=True)) for values in db.execute(query)]


def task_frame(row: Any, rows: list[dict[str, Any]]) -> pd.DataFrame:
    """The rows as a typed table: the keys' types, then each column's declared type."""
    cols = _columns(row)
    dtypes = {c.name: _dtype(c) for c in cols}
    for c in cols:  # times as the exports write them: UTC
        if dtypes[c.name].startswith("datetime"):
            for r in rows:
                value = r.get(c.name)
                if value is not None and value.tzinfo is None:
                    r[c.name] = pd.Timestamp(value, tz="UTC")
    return tidy.frame(rows, [*KEYS, *(c.name for c in cols)], dtypes)
