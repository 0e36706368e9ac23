"""What every task's records stand on: the declarative base of the study database, the trial
row (the protocol's unit: a task's state and status), and the helpers record columns use.

A task declares its record tables on :class:`Base` (``tasks/<task>/tables.py``); the study
stores the rows a task's step makes in the step's one transaction. Times are stored in UTC;
JSON columns hold compact JSON (:func:`dumps`, :func:`numbers_json`).
"""

from __future__ import annotations

import hashlib
import json
from datetime import UTC, datetime
from typing import Any, cast

import orjson
from sqlalchemy import (
    BigInteger,
    DateTime,
    ForeignKey,
    Integer,
    String,
    Table,
    Text,
    UniqueConstraint,
    text,
)
from sqlalchemy.orm import DeclarativeBase, Mapped, Session, mapped_column


def utcnow() -> datetime:
    return datetime.now(UTC)


def as_utc(t: datetime | None) -> datetime | None:
    """SQLite returns naive datetimes: they were stored in UTC."""
    if t is None:
        return None
    return t.replace(tzinfo=UTC) if t.tzinfo is None else t.astimezone(UTC)


def dumps(value: Any) -> str:
    return json.dumps(value, separators=(",", ":"))


def numbers_json(values: list[Any] | None) -> str:
    """A list of finite numbers (or nested lists of them, or None) as compact JSON (orjson: the same shortest round-trip decimals
    as Python's ``repr``, several times faster; it would write NaN as null, so callers pass
    finite numbers only)."""
    return orjson.dumps(values).decode()


class Base(DeclarativeBase):
    pass


def core_table(row: type[Base]) -> Table:
    """The Core table of a row class, for plain inserts (no ORM unit of work)."""
    return cast(Table, row.__table__)


Stamp = DateTime(timezone=True)


def elapsed_ms(later: datetime, earlier: datetime | None) -> float:
    """Milliseconds from ``earlier`` to ``later`` (0 when there is no earlier time)."""
    e = as_utc(earlier)
    later_utc = as_utc(later)
    if e is None or later_utc is None:
        return 0.0
    return max(0.0, (later_utc - e).total_seconds() * 1000.0)


def server_ms(later: datetime, shown_at: datetime | None, load_ms: float | None) -> float:
    """``server_response_ms``: from what was answered stored to the answer received, less the
    page's reported loading time (so a first screen does not count page and model loading)."""
    return max(0.0, elapsed_ms(later, shown_at) - (load_ms or 0.0))


class TrialRow(Base):
    """One trial of a session: its block and task, its condition, seed and status, and the task's
    state (``engine_state``: JSON the task reads back; the name is the GA's, kept for old
    databases). ``attempt`` counts restarts (a task without restarts keeps 0)."""

    __tablename__ = "trials"
    __table_args__ = (UniqueConstraint("session_id", "position", name="uq_trials_position"),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    session_id: Mapped[int] = mapped_column(ForeignKey("sessions.id"), index=True)
    position: Mapped[int] = mapped_column(Integer)
    #: The block (0-based, config order) and the task it runs (``evolve``, ``categorise``).
    block: Mapped[int] = mapped_column(Integer, server_default="0")
    task: Mapped[str] = mapped_column(String(16), server_default="evolve")
    condition: Mapped[int] = mapped_column(Integer)
    emotion: Mapped[str] = mapped_column(String(64))
    identity: Mapped[str] = mapped_column(String(64))
    repetition: Mapped[int] = mapped_column(Integer)
    seed: Mapped[int] = mapped_column(BigInteger)
    #: pending → active → rating → done
    status: Mapped[str] = mapped_column(String(16))
    attempt: Mapped[int] = mapped_column(Integer)
    generation: Mapped[int] = mapped_column(Integer)
    engine_state: Mapped[str | None] = mapped_column(Text, nullable=True)
    final_face_id: Mapped[int | None] = mapped_column(Integer, nullable=True)
    started_at: Mapped[datetime | None] = mapped_column(Stamp, nullable=True)
    finished_at: Mapped[datetime | None] = mapped_column(Stamp, nullable=True)


def fields_of(command: Any, row: Any) -> dict[str, Any]:
    """The command's values of the fields its record's row has columns of (a field is named
    once, in the command and the record, never copied by hand)."""
    columns = set(core_table(row).columns.keys())
    return {k: v for k, v in command.model_dump().items() if k in columns}


def lock_shared(db: Session, *key: object) -> None:
    """Hold, until the step's transaction ends, the lock of state that several sessions share
    (``key`` names it: a task's name and what it shares, e.g. a block's chains of one concept).

    Each step already holds its own session's row; a task whose state is shared between
    sessions takes this lock before reading it, then no two steps of different sessions read
    and change it at once. PostgreSQL: a transaction-level advisory lock on a 63-bit hash of the
    key (taken after the session's row lock, always in that order: no deadlock); SQLite runs
    one writing transaction at a time, so there is nothing more to lock."""
    if db.get_bind().dialect.name != "postgresql":
        return
    digest = hashlib.sha256(repr(key).encode()).digest()
    db.execute(
        text("SELECT pg_advisory_xact_lock(:k)"),
        {"k": int.from_bytes(digest[:8], "big") >> 1},
    )
