"""The study's tables (SQLAlchemy 2.x declarative rows) and the helpers their columns use.

Times are stored in UTC; JSON columns hold compact JSON (``dumps``). The schema is created and
upgraded by Alembic (``emogen/study/migrations``); :data:`SCHEMA_VERSION` goes into every export.
"""

from __future__ import annotations

import json
from datetime import UTC, datetime
from typing import Any, cast

import orjson
from sqlalchemy import (
    BigInteger,
    Boolean,
    DateTime,
    Float,
    ForeignKey,
    Index,
    Integer,
    String,
    Table,
    Text,
    UniqueConstraint,
)
from sqlalchemy.orm import DeclarativeBase, Mapped, mapped_column, relationship

#: 2: sessions.user_agent may be NULL (not collected), selections/restarts.load_ms, the
#: export's ``study`` table. Records of schema 1 still open, export and replay.
#: 3 (exports only, the database is unchanged): typed columns (UTC timestamps in Parquet,
#: seeds ``s<digits>`` in CSV, NA not −1 for ``order_row``/``parent_a``/``parent_b``),
#: ``sessions.trial_order`` dropped (the ``trials`` table holds the order), provenance in
#: every Parquet file's metadata (:mod:`emogen.columns`). Exports of schema 2 still analyse
#: and replay.
#: 5: blocks and tasks: ``trials.block`` and ``trials.task``, the ``responses`` table (a
#: categorise trial's face and answer). Exports of schema 4 still analyse and replay.
#: 6 (exports only): tables named by their task (``responses`` → ``categorise_responses``,
#: ``ratings`` → ``evolve_ratings``), the ``final_faces`` table, ``trials.emotion`` and
#: ``final_face_id`` NA for trials that make no face. Exports of schema 5 still analyse and replay.
SCHEMA_VERSION = "emogen.study/6"


def utcnow() -> datetime:
    return datetime.now(UTC)


def as_utc(t: datetime | None) -> datetime | None:
    """SQLite returns naive datetimes: they were stored in UTC."""
    if t is None:
        return None
    return t.replace(tzinfo=UTC) if t.tzinfo is None else t.astimezone(UTC)


def dumps(value: Any) -> str:
    return json.dumps(value, separators=(",", ":"))


def numbers_json(values: list[float]) -> str:
    """A list of finite numbers as compact JSON (orjson: the same shortest round-trip decimals
    as Python's ``repr``, several times faster; it would write NaN as null, so callers pass
    finite numbers only)."""
    return orjson.dumps(values).decode()


class Base(DeclarativeBase):
    pass


def core_table(row: type[Base]) -> Table:
    """The Core table of a row class, for plain inserts (no ORM unit of work)."""
    return cast(Table, row.__table__)


Stamp = DateTime(timezone=True)


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

    study: Mapped[StudyRow] = relationship()
    trials: Mapped[list[TrialRow]] = relationship(
        back_populates="session", order_by="TrialRow.position"
    )


class TrialRow(Base):
    """One trial (an emotion × identity × repetition) of a session; ``attempt`` counts restarts."""

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

    session: Mapped[SessionRow] = relationship(back_populates="trials")


class PopulationRow(Base):
    """One generation shown: stored before it is sent to the participant."""

    __tablename__ = "populations"
    __table_args__ = (
        UniqueConstraint("trial_id", "attempt", "generation", name="uq_populations_generation"),
    )

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    trial_id: Mapped[int] = mapped_column(ForeignKey("trials.id"), index=True)
    attempt: Mapped[int] = mapped_column(Integer)
    generation: Mapped[int] = mapped_column(Integer)
    shown_at: Mapped[datetime] = mapped_column(Stamp)

    faces: Mapped[list[FaceRow]] = relationship(order_by="FaceRow.position")


class FaceRow(Base):
    """One face of a population: engine face id, parents, operator, genes and full weights."""

    __tablename__ = "faces"
    __table_args__ = (
        UniqueConstraint("population_id", "position", name="uq_faces_position"),
        UniqueConstraint("population_id", "face_id", name="uq_faces_face_id"),
    )

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    population_id: Mapped[int] = mapped_column(ForeignKey("populations.id"), index=True)
    position: Mapped[int] = mapped_column(Integer)
    face_id: Mapped[int] = mapped_column(Integer)
    parent_a: Mapped[int] = mapped_column(Integer)
    parent_b: Mapped[int] = mapped_column(Integer)
    operator: Mapped[str] = mapped_column(String(32))
    #: JSON lists of floats (exact: shortest round-trip repr).
    genes: Mapped[str] = mapped_column(Text)
    weights: Mapped[str] = mapped_column(Text)


class SelectionRow(Base):
    """A participant's selection in one population (one per population, ever)."""

    __tablename__ = "selections"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    population_id: Mapped[int] = mapped_column(ForeignKey("populations.id"), unique=True)
    trial_id: Mapped[int] = mapped_column(ForeignKey("trials.id"), index=True)
    elite_face_id: Mapped[int] = mapped_column(Integer)
    #: JSON list of the other selected face ids, in the order they were told.
    other_face_ids: Mapped[str] = mapped_column(Text)
    submitted_at: Mapped[datetime] = mapped_column(Stamp)
    server_response_ms: Mapped[float] = mapped_column(Float)
    client_response_ms: Mapped[float | None] = mapped_column(Float, nullable=True)
    #: The page's load time of the population (ms), if it reported it (schema 2).
    load_ms: Mapped[float | None] = mapped_column(Float, nullable=True)
    step_key: Mapped[str] = mapped_column(String(64))


class RestartRow(Base):
    """'Start again' pressed while a population was shown."""

    __tablename__ = "restarts"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    population_id: Mapped[int] = mapped_column(ForeignKey("populations.id"), unique=True)
    trial_id: Mapped[int] = mapped_column(ForeignKey("trials.id"), index=True)
    submitted_at: Mapped[datetime] = mapped_column(Stamp)
    server_response_ms: Mapped[float] = mapped_column(Float)
    client_response_ms: Mapped[float | None] = mapped_column(Float, nullable=True)
    #: The page's load time of the population (ms), if it reported it (schema 2).
    load_ms: Mapped[float | None] = mapped_column(Float, nullable=True)
    step_key: Mapped[str] = mapped_column(String(64))


class RatingRow(Base):
    """The satisfaction rating of a trial's final face."""

    __tablename__ = "ratings"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    trial_id: Mapped[int] = mapped_column(ForeignKey("trials.id"), unique=True)
    face_id: Mapped[int] = mapped_column(Integer)
    value: Mapped[int] = mapped_column(Integer)
    points: Mapped[int] = mapped_column(Integer)
    submitted_at: Mapped[datetime] = mapped_column(Stamp)
    server_response_ms: Mapped[float] = mapped_column(Float)
    client_response_ms: Mapped[float | None] = mapped_column(Float, nullable=True)
    step_key: Mapped[str] = mapped_column(String(64))


class StimulusRow(Base):
    """The face a categorise trial shows, fixed when its block starts (before it is shown):
    where it comes from, the labels offered in their order, its identity and full weights."""

    __tablename__ = "stimuli"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    trial_id: Mapped[int] = mapped_column(ForeignKey("trials.id"), unique=True)
    #: own / other / file / random; ``fallback``: a face standing in for an other's face.
    source: Mapped[str] = mapped_column(String(16))
    fallback: Mapped[bool] = mapped_column(Boolean, default=False)
    #: An own or other face: the session, trial (position) and face id it was made in.
    source_session_id: Mapped[int | None] = mapped_column(Integer, nullable=True)
    source_trial: Mapped[int | None] = mapped_column(Integer, nullable=True)
    source_face_id: Mapped[int | None] = mapped_column(Integer, nullable=True)
    #: A file face: its row (0-based, as read); a random face: its kind (protocol label).
    source_row: Mapped[int | None] = mapped_column(Integer, nullable=True)
    source_label: Mapped[str | None] = mapped_column(String(64), nullable=True)
    #: The emotion the face was made for (own, other; a file's label column), if known.
    intended: Mapped[str | None] = mapped_column(String(64), nullable=True)
    identity: Mapped[str] = mapped_column(String(64))
    #: JSON lists: genes (random faces; own/other: the source face's), full weights, labels.
    genes: Mapped[str | None] = mapped_column(Text, nullable=True)
    weights: Mapped[str] = mapped_column(Text)
    labels: Mapped[str] = mapped_column(Text)
    shown_at: Mapped[datetime | None] = mapped_column(Stamp, nullable=True)


class ResponseRow(Base):
    """A categorisation: the label chosen (or ``none``), its position among those offered,
    the intensity and confidence ratings if asked, and the times."""

    __tablename__ = "responses"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    trial_id: Mapped[int] = mapped_column(ForeignKey("trials.id"), unique=True)
    label: Mapped[str] = mapped_column(String(64))
    label_position: Mapped[int] = mapped_column(Integer)
    intensity: Mapped[int | None] = mapped_column(Integer, nullable=True)
    confidence: Mapped[int | None] = mapped_column(Integer, nullable=True)
    submitted_at: Mapped[datetime] = mapped_column(Stamp)
    server_response_ms: Mapped[float] = mapped_column(Float)
    client_response_ms: Mapped[float | None] = mapped_column(Float, nullable=True)
    load_ms: Mapped[float | None] = mapped_column(Float, nullable=True)
    step_key: Mapped[str] = mapped_column(String(64))


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
