"""The study's tables (SQLAlchemy 2.x declarative rows) and the helpers their columns use.

Times are stored in UTC; JSON columns hold compact JSON (``dumps``). The schema is created and
upgraded by Alembic (``emogen/study/migrations``); :data:`SCHEMA_VERSION` goes into every export.
"""

from __future__ import annotations

from datetime import datetime

from sqlalchemy import (
    BigInteger,
    Float,
    ForeignKey,
    Index,
    Integer,
    String,
    Table,
    Text,
    UniqueConstraint,
)
from sqlalchemy.orm import Mapped, mapped_column

from emogen.tasks.records import (
    Base,
    Stamp,
    TrialRow,
    as_utc,
    core_table,
    dumps,
    numbers_json,
    utcnow,
)
from emogen.tasks.registry import TASKS

__all__ = [
    "SCHEMA_VERSION",
    "Base",
    "ResearcherFailureRow",
    "SessionRow",
    "StepRow",
    "StudyRow",
    "TrialRow",
    "as_utc",
    "core_table",
    "dumps",
    "numbers_json",
    "task_tables",
    "utcnow",
]

#: 2: sessions.user_agent may be NULL (not collected), selections/restarts.load_ms, the
#: export's ``study`` table. Records of schema 1 still open, export and replay.
#: 3 (exports only, the database is unchanged): typed columns (UTC timestamps in Parquet,
#: seeds ``s<digits>`` in CSV, NA not −1 for ``order_row``/``parent_a``/``parent_b``),
#: ``sessions.trial_order`` dropped (the ``trials`` table holds the order), provenance in
#: every Parquet file's metadata (:mod:`emogen.columns`). Exports of schema 2 still analyse
#: and replay.
#: 5: blocks and tasks: ``trials.block`` and ``trials.task``, a table of answers (a
#: labelling trial's face and answer). Exports of schema 4 still analyse and replay.
#: 6 (exports only): each task's tables named by their task (the names: docs/data.md), the
#: ``final_faces`` table, ``trials.emotion`` and ``final_face_id`` NA for trials that make no
#: face. Exports of schema 5 still analyse and replay.
#: 7: the steps of a task that shows faces say which display the page had (``fallback``: the
#: server's images, not the 3D viewer; NA before; docs/data.md). Records and exports of
#: schema 6 still open, analyse and replay.
SCHEMA_VERSION = "emogen.study/7"


class StudyRow(Base):
    """One study config as served (a changed config is a new row)."""

    __tablename__ = "studies"
    __table_args__ = (UniqueConstraint("name", "config_hash", name="uq_studies_name_hash"),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    name: Mapped[str] = mapped_column(String(64))
    config_hash: Mapped[str] = mapped_column(String(64))
    config_json: Mapped[str] = mapped_column(Text)
    model_name: Mapped[str] = mapped_column(String(128))
    model_hash: Mapped[str] = mapped_column(String(128))
    #: JSON lists: gene names and full weight column names (shapes, then correctives).
    gene_names: Mapped[str] = mapped_column(Text)
    weight_names: Mapped[str] = mapped_column(Text)
    package_version: Mapped[str] = mapped_column(String(32))
    created_at: Mapped[datetime] = mapped_column(Stamp)


class SessionRow(Base):
    """One participant's session; ``token`` is the participant's secret, ``id`` the researcher's."""

    __tablename__ = "sessions"
    __table_args__ = (
        UniqueConstraint("study_id", "participant_id", name="uq_sessions_participant"),
        UniqueConstraint("study_id", "number", name="uq_sessions_number"),
        Index("ix_sessions_create_key", "study_id", "create_key"),
    )

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    study_id: Mapped[int] = mapped_column(ForeignKey("studies.id"), index=True)
    token: Mapped[str] = mapped_column(String(64), unique=True)
    participant_id: Mapped[str] = mapped_column(String(128))
    participant_source: Mapped[str] = mapped_column(String(16))
    number: Mapped[int] = mapped_column(Integer)
    seed: Mapped[int] = mapped_column(BigInteger)
    order_kind: Mapped[str] = mapped_column(String(16))
    order_row: Mapped[int] = mapped_column(Integer)
    trial_order: Mapped[str] = mapped_column(Text)
    #: instructions → trial → done
    stage: Mapped[str] = mapped_column(String(16))
    current_trial: Mapped[int] = mapped_column(Integer)
    package_version: Mapped[str] = mapped_column(String(32))
    #: NULL unless the study collects it (``collect_user_agent``).
    user_agent: Mapped[str | None] = mapped_column(String(256), nullable=True)
    #: SHA-256 (hex) of the creation key the consent page sent: a retried create with the same
    #: key gets this session again (NULL: none sent, or made before schema revision 0004).
    create_key: Mapped[str | None] = mapped_column(String(64), nullable=True)
    created_at: Mapped[datetime] = mapped_column(Stamp)
    consented_at: Mapped[datetime] = mapped_column(Stamp)
    started_at: Mapped[datetime | None] = mapped_column(Stamp, nullable=True)
    completed_at: Mapped[datetime | None] = mapped_column(Stamp, nullable=True)
    updated_at: Mapped[datetime] = mapped_column(Stamp)


class ResearcherFailureRow(Base):
    """Wrong researcher tokens of one client address: a token bucket (``tokens`` left at
    ``updated``, seconds since the epoch) shared by every worker process on the database."""

    __tablename__ = "researcher_failures"

    client: Mapped[str] = mapped_column(String(64), primary_key=True)
    tokens: Mapped[float] = mapped_column(Float)
    updated: Mapped[float] = mapped_column(Float)


class StepRow(Base):
    """Idempotency keys: a step submitted twice with the same key is done once."""

    __tablename__ = "steps"
    __table_args__ = (UniqueConstraint("session_id", "key", name="uq_steps_key"),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    session_id: Mapped[int] = mapped_column(ForeignKey("sessions.id"), index=True)
    key: Mapped[str] = mapped_column(String(64))
    kind: Mapped[str] = mapped_column(String(16))
    request_hash: Mapped[str] = mapped_column(String(64))
    created_at: Mapped[datetime] = mapped_column(Stamp)


def task_tables() -> list[Table]:
    """The record tables of every registered task (declared on :class:`Base` by the tasks)."""
    return [core_table(row) for task in TASKS.values() for row in task.tables]
