"""Study storage: SQLAlchemy 2.x tables, engines for SQLite (WAL) and PostgreSQL, migrations.

SQLite is the default (a file in the user data folder); PostgreSQL by URL
(``postgresql://user@host/db``, driven by psycopg 3). The schema is created and upgraded by
Alembic (``emogen/study/migrations``) when a :class:`Store` opens, so a server, the CLI and the
tests always see the current schema.

Durability: SQLite runs in WAL mode with ``synchronous=FULL`` and foreign keys on; every step is
one transaction, committed before the server answers. Writes are serialised per session: on
SQLite by ``BEGIN IMMEDIATE`` (and an in-process lock, so concurrent requests queue instead of
polling), on PostgreSQL by ``SELECT … FOR UPDATE`` on the session row.
"""

from __future__ import annotations

import json
import os
import queue
import threading
from collections.abc import Callable, Iterator
from concurrent.futures import Future
from contextlib import contextmanager
from datetime import UTC, datetime
from pathlib import Path
from typing import Any, TypeVar

from sqlalchemy import (
    BigInteger,
    DateTime,
    Float,
    ForeignKey,
    Integer,
    String,
    Text,
    UniqueConstraint,
    create_engine,
    event,
    text,
)
from sqlalchemy.engine import Engine, make_url
from sqlalchemy.orm import DeclarativeBase, Mapped, Session, mapped_column, relationship

from emogen.errors import ConfigError

T = TypeVar("T")
SCHEMA_VERSION = "emogen.study/1"
DATABASE_ENV = "EMOGEN_DATABASE_URL"


def utcnow() -> datetime:
    return datetime.now(UTC)


def as_utc(t: datetime | None) -> datetime | None:
    """SQLite returns naive datetimes: they were stored in UTC."""
    if t is None:
        return None
    return t.replace(tzinfo=UTC) if t.tzinfo is None else t.astimezone(UTC)


def dumps(value: Any) -> str:
    return json.dumps(value, separators=(",", ":"))


class Base(DeclarativeBase):
    pass


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
    user_agent: Mapped[str] = mapped_column(String(256))
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


# ---- engines ---------------------------------------------------------------------------------
def default_database_url() -> str:
    import platformdirs

    folder = Path(platformdirs.user_data_dir("emogen", appauthor=False))
    return f"sqlite:///{folder / 'study.sqlite'}"


def resolve_database_url(option: str | None = None, config_url: str | None = None) -> str:
    """--database-url, then $EMOGEN_DATABASE_URL, then the study config, then the default file."""
    return option or os.environ.get(DATABASE_ENV) or config_url or default_database_url()


def normalise_url(url: str) -> str:
    """``postgres://`` and ``postgresql://`` use psycopg 3; a bare path means an SQLite file."""
    for prefix in ("postgres://", "postgresql://"):
        if url.startswith(prefix):
            return "postgresql+psycopg://" + url[len(prefix) :]
    if "://" not in url:
        return f"sqlite:///{Path(url).expanduser().resolve()}"
    return url


def _sqlite_pragmas(dbapi_conn: Any, _record: Any) -> None:
    dbapi_conn.isolation_level = None  # SQLAlchemy's begin event issues BEGIN itself
    cur = dbapi_conn.cursor()
    cur.execute("PRAGMA journal_mode=WAL")
    cur.execute("PRAGMA synchronous=FULL")
    cur.execute("PRAGMA foreign_keys=ON")
    cur.execute("PRAGMA busy_timeout=30000")
    cur.close()


def _sqlite_begin(conn: Any) -> None:
    mode = conn.get_execution_options().get("sqlite_begin", "")
    conn.exec_driver_sql(f"BEGIN {mode}".strip())


def make_engine(url: str) -> Engine:
    url = normalise_url(url)
    try:
        parsed = make_url(url)
    except Exception as exc:  # sqlalchemy.exc.ArgumentError
        raise ConfigError(f"database URL {url!r} is not valid: {exc}") from None
    if parsed.get_backend_name() == "sqlite":
        db = parsed.database
        if not db or db == ":memory:":
            raise ConfigError("database URL must name an SQLite file (':memory:' is not durable)")
        Path(db).expanduser().parent.mkdir(parents=True, exist_ok=True)
        engine = create_engine(
            parsed, connect_args={"timeout": 30, "check_same_thread": False}, pool_size=8
        )
        event.listen(engine, "connect", _sqlite_pragmas)
        event.listen(engine, "begin", _sqlite_begin)
        return engine
    if parsed.get_backend_name() != "postgresql":
        raise ConfigError(
            f"database URL must be sqlite:///FILE or postgresql://…; got {parsed.drivername}"
        )
    return create_engine(parsed, pool_size=10, max_overflow=20, pool_pre_ping=True)


class _GroupCommit:
    """SQLite group commit: one writer thread runs queued write jobs, many per transaction.

    Each job runs in its own SAVEPOINT (a failing job is rolled back alone and its caller gets
    the exception); one COMMIT — one fsync — then makes the whole batch durable, and only then
    are the callers answered. Under load this shares the fsync among concurrent steps; alone, a
    job is a transaction of its own as before.
    """

    MAX_BATCH = 32

    def __init__(self, store: Store) -> None:
        self.store = store
        self.jobs: queue.SimpleQueue[tuple[Callable[[Session], Any], Future[Any]] | None] = (
            queue.SimpleQueue()
        )
        self.thread: threading.Thread | None = None
        self.start_lock = threading.Lock()

    def submit(self, fn: Callable[[Session], T]) -> T:
        future: Future[T] = Future()
        with self.start_lock:
            if self.thread is None or not self.thread.is_alive():
                self.thread = threading.Thread(
                    target=self._run, name="emogen-sqlite-writer", daemon=True
                )
                self.thread.start()
        self.jobs.put((fn, future))
        return future.result()

    def stop(self) -> None:
        with self.start_lock:
            if self.thread is not None and self.thread.is_alive():
                self.jobs.put(None)
                self.thread.join(5)
            self.thread = None

    def _run(self) -> None:
        while True:
            job = self.jobs.get()
            if job is None:
                return
            batch = [job]
            while len(batch) < self.MAX_BATCH:
                try:
                    more = self.jobs.get_nowait()
                except queue.Empty:
                    break
                if more is None:
                    self.jobs.put(None)  # stop after this batch
                    break
                batch.append(more)
            self._execute(batch)

    def _execute(self, batch: list[tuple[Callable[[Session], Any], Future[Any]]]) -> None:
        outcomes: list[tuple[Future[Any], Any, BaseException | None]] = []
        try:
            with (
                self.store._lock or threading.Lock(),
                Session(self.store._write_engine, expire_on_commit=False) as session,
                session.begin(),
            ):
                for fn, future in batch:
                    session.info.clear()
                    try:
                        with session.begin_nested():
                            result = fn(session)
                            session.flush()
                        outcomes.append((future, result, None))
                    except Exception as exc:  # the caller gets it
                        outcomes.append((future, None, exc))
        except Exception as exc:  # the commit failed: nobody's step was stored
            for _fn, future in batch:
                if not future.done():
                    future.set_exception(exc)
            return
        for future, result, error in outcomes:
            if error is not None:
                future.set_exception(error)
            else:
                future.set_result(result)


class Store:
    """A database: migrated on open; ``read()``, ``write()`` and ``transact()`` transactions."""

    def __init__(self, url: str, *, migrate: bool = True) -> None:
        self.url = normalise_url(url)
        self.engine = make_engine(self.url)
        self.is_sqlite = self.engine.dialect.name == "sqlite"
        self._write_engine = (
            self.engine.execution_options(sqlite_begin="IMMEDIATE")
            if self.is_sqlite
            else self.engine
        )
        self._lock = threading.Lock() if self.is_sqlite else None
        self._group = _GroupCommit(self) if self.is_sqlite else None
        if migrate:
            self.migrate()

    def migrate(self) -> None:
        from emogen.study.migrations import upgrade

        upgrade(self)

    @contextmanager
    def read(self) -> Iterator[Session]:
        with Session(self.engine, expire_on_commit=False) as session, session.begin():
            yield session

    @contextmanager
    def write(self) -> Iterator[Session]:
        """One transaction, committed on exit (rolled back on an exception)."""
        if self._lock is not None:
            with (
                self._lock,
                Session(self._write_engine, expire_on_commit=False) as session,
                session.begin(),
            ):
                yield session
            return
        with Session(self.engine, expire_on_commit=False) as session, session.begin():
            yield session

    def transact(self, fn: Callable[[Session], T]) -> T:
        """``fn(session)`` in a write transaction; returns its result once it is committed.

        On SQLite concurrent calls share commits (see :class:`_GroupCommit`); on PostgreSQL
        each call is its own transaction.
        """
        if self._group is not None:
            return self._group.submit(fn)
        with Session(self.engine, expire_on_commit=False) as session, session.begin():
            return fn(session)

    def dispose(self) -> None:
        if self._group is not None:
            self._group.stop()
        self.engine.dispose()

    def ping(self) -> None:
        with self.engine.connect() as conn:
            conn.execute(text("SELECT 1"))

    def describe(self) -> str:
        return self.engine.url.render_as_string(hide_password=True)
