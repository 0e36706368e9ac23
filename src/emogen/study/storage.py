"""Study storage: engines for SQLite (WAL) and PostgreSQL, transactions, migrations on open.

SQLite is the default (a file in the user data folder); PostgreSQL by URL
(``postgresql://user@host/db``, driven by psycopg 3). The schema is created and upgraded by
Alembic (``emogen/study/migrations``) when a :class:`Store` opens, so a server, the CLI and the
tests always see the current schema.

Durability: SQLite runs in WAL mode with ``synchronous=FULL`` and foreign keys on; every step is
one transaction, committed before the server answers. Writes are serialised per session: on
SQLite by ``BEGIN IMMEDIATE`` (and, so that concurrent requests queue instead of polling the
database's busy lock, an in-process lock and an exclusive ``flock`` on ``<database>.writer-lock``
shared by every process of the server), on PostgreSQL by ``SELECT … FOR UPDATE`` on the session
row.

A full disk or a read-only database is named as such (:func:`storage_problem`), never as a
busy database: :meth:`Store.check_writable` refuses to start on one, a write that fails on
one is remembered until a write succeeds, and :meth:`Store.health_problem` reports it (and,
on SQLite, a read-only file system or under :data:`MIN_FREE_BYTES` free) for ``/healthz``.
"""

from __future__ import annotations

import fcntl
import os
import queue
import threading
from collections.abc import Callable, Iterator
from concurrent.futures import Future
from contextlib import contextmanager
from pathlib import Path
from typing import Any, TypeVar

from sqlalchemy import text
from sqlalchemy.engine import Engine
from sqlalchemy.orm import Session

from emogen.errors import ResourceError
from emogen.study.engines import DATABASE_ENV, make_engine, normalise_url

T = TypeVar("T")
#: Free bytes under which an SQLite database's disk counts as full (a session writes ~1 MB).
MIN_FREE_BYTES = 16 * 1024 * 1024


def storage_problem(exc: BaseException) -> str | None:
    """What a database error says of the storage itself (a full disk, a read-only database),
    or None for any other error."""
    orig = getattr(exc, "orig", None) or exc
    text = str(orig).lower()
    state = getattr(orig, "sqlstate", None)
    if state == "53100" or "disk is full" in text or "no space left" in text:
        return "the disk of the study database is full"
    if state == "25006" or "readonly database" in text or "read-only" in text:
        return "the study database is read-only"
    return None


# ---- engines ---------------------------------------------------------------------------------
def default_database_url() -> str:
    import platformdirs

    folder = Path(platformdirs.user_data_dir("emogen", appauthor=False))
    return f"sqlite:///{folder / 'study.sqlite'}"


def resolve_database_url(option: str | None = None, config_url: str | None = None) -> str:
    """--database-url, then $EMOGEN_DATABASE_URL, then the study config, then the default file."""
    return option or os.environ.get(DATABASE_ENV) or config_url or default_database_url()


def _is_connection_error(exc: Exception) -> bool:
    """A database error that says the database cannot be reached or opened (not a bad query)."""
    from sqlalchemy.exc import InterfaceError, OperationalError

    return isinstance(exc, OperationalError | InterfaceError)


def _writer_lock_path(engine: Engine) -> str:
    """``<database file>.writer-lock``: the lock file the writers of one SQLite file share."""
    return f"{engine.url.database}.writer-lock"


class _GroupCommit:
    """SQLite group commit: one writer thread runs queued write jobs, many per transaction.

    Each job of a batch runs in its own SAVEPOINT (a failing job is rolled back alone and its caller gets
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
        if len(batch) == 1:  # alone: its own transaction, no savepoint needed
            fn, future = batch[0]
            try:
                with (
                    self.store._writer(),
                    Session(self.store._write_engine, expire_on_commit=False) as session,
                    session.begin(),
                ):
                    result = fn(session)
                    session.flush()
            except Exception as exc:  # rolled back: the caller gets it
                future.set_exception(exc)
            else:
                future.set_result(result)
            return
        outcomes: list[tuple[Future[Any], Any, BaseException | None]] = []
        try:
            with (
                self.store._writer(),
                Session(self.store._write_engine, expire_on_commit=False) as session,
                session.begin(),
            ):
                for fn, future in batch:
                    session.info.clear()
                    # each job sees the database, not the objects an earlier job loaded (a
                    # job may change rows by plain statements, which those would not show)
                    session.expunge_all()
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

    def __init__(self, url: str, *, migrate: bool = True, create: bool = True) -> None:
        """``create=False``: open an existing database only (for commands that only read)."""
        self.url = normalise_url(url)
        self.engine = make_engine(self.url, create=create)
        self.is_sqlite = self.engine.dialect.name == "sqlite"
        #: opened read-only (SQLite, create=False, of the current schema): nothing is written,
        #: so a read-only copy (an archive) opens; an older schema is opened to be upgraded
        self.read_only = self.is_sqlite and not create and self._current_schema()
        if self.is_sqlite and not create and not self.read_only:
            self.engine.dispose()
            self.engine = make_engine(self.url)
        self._write_engine = (
            self.engine.execution_options(sqlite_begin="IMMEDIATE")
            if self.is_sqlite
            else self.engine
        )
        self._lock = threading.Lock() if self.is_sqlite else None
        self._lock_path = _writer_lock_path(self.engine) if self.is_sqlite else None
        self._group = _GroupCommit(self) if self.is_sqlite else None
        #: the storage problem the last failed write met (cleared by a write that succeeds)
        self.write_problem: str | None = None
        if migrate and not self.read_only:
            self.migrate()

    def _current_schema(self) -> bool:
        """Whether the database is of the current schema (read without writing)."""
        from sqlalchemy.exc import DBAPIError

        from emogen.study.migrations import HEAD, stored_revision

        try:
            return stored_revision(self.engine) == HEAD
        except DBAPIError:
            return False  # opened to be upgraded: its error is named there

    def migrate(self) -> None:
        from sqlalchemy.exc import DBAPIError

        from emogen.study.migrations import upgrade
        from emogen.study.tables import Base, task_tables

        try:
            upgrade(self._write_engine)
            # a registered task's tables that no migration made (a lab's own task): made here
            Base.metadata.create_all(self._write_engine, tables=task_tables(), checkfirst=True)
        except DBAPIError as exc:
            self.engine.dispose()
            # SQLite says "disk I/O error" when a full disk stops its journal: the disk says why
            problem = storage_problem(exc) or self._disk_problem()
            if problem is not None:
                raise self._cannot_save(problem) from None
            if not _is_connection_error(exc) and "not a database" not in str(exc.orig):
                raise
            first = str(exc.orig).strip().splitlines()[0] if exc.orig else type(exc).__name__
            hint = (
                "is it a study database, and may you read and write it and its folder?"
                if self.is_sqlite
                else "is the server running, and are the URL, user and password right?"
            )
            raise ResourceError(
                f"cannot open the study database {self.describe()}: {first} ({hint})"
            ) from None

    @contextmanager
    def _writer(self) -> Iterator[None]:
        """SQLite: this process's lock, then the lock every process of the server shares (a
        blocking ``flock``: a waiting writer is woken when the lock is free, where SQLite's
        own busy handler would sleep and poll)."""
        if self._lock is None or self._lock_path is None:
            yield
            return
        with self._lock:
            fd = os.open(self._lock_path, os.O_RDWR | os.O_CREAT, 0o600)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX)
                yield
            finally:
                os.close(fd)  # releases the flock

    @contextmanager
    def read(self) -> Iterator[Session]:
        with Session(self.engine, expire_on_commit=False) as session, session.begin():
            yield session

    @contextmanager
    def write(self) -> Iterator[Session]:
        """One transaction, committed on exit (rolled back on an exception)."""
        if self._lock is not None:
            with (
                self._writer(),
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
        from sqlalchemy.exc import DBAPIError

        try:
            if self._group is not None:
                result = self._group.submit(fn)
            else:
                with Session(self.engine, expire_on_commit=False) as session, session.begin():
                    result = fn(session)
        except DBAPIError as exc:
            self.write_problem = storage_problem(exc) or self.write_problem
            raise
        self.write_problem = None
        return result

    def _disk_problem(self) -> str | None:
        """SQLite: its folder on a read-only file system, or under MIN_FREE_BYTES free."""
        if not self.is_sqlite:
            return None
        try:
            stat = os.statvfs(Path(str(self.engine.url.database)).expanduser().parent)
        except OSError:
            return None
        if stat.f_flag & os.ST_RDONLY:
            return "the study database is read-only (its file system is mounted read-only)"
        free = stat.f_bavail * stat.f_frsize
        if free < MIN_FREE_BYTES:
            return f"the disk of the study database is full ({free // 1024} KiB free)"
        return None

    def health_problem(self) -> str | None:
        """Why the database cannot save participants' steps now, or None."""
        return self.write_problem or self._disk_problem()

    def check_writable(self) -> None:
        """Refuse (``ResourceError``) a database that cannot be written: a full disk, a
        read-only file or server. Writes nothing but the header's own value back (SQLite)."""
        from sqlalchemy.exc import DBAPIError

        problem = self._disk_problem()
        if problem is None:
            try:
                with self.write() as db:
                    if self.is_sqlite:
                        version = db.execute(text("PRAGMA user_version")).scalar()
                        db.execute(text(f"PRAGMA user_version = {int(version or 0)}"))
                    elif db.execute(text("SHOW transaction_read_only")).scalar() == "on":
                        problem = "the study database is read-only (a standby or read-only server)"
            except DBAPIError as exc:
                problem = storage_problem(exc)
                if problem is None:
                    raise
        if problem is not None:
            raise self._cannot_save(problem)

    def _cannot_save(self, problem: str) -> ResourceError:
        return ResourceError(
            f"cannot save anything in {self.describe()}: {problem}; free space on its disk "
            "or make it writable, then start again"
        )

    def dispose(self) -> None:
        if self._group is not None:
            self._group.stop()
        self.engine.dispose()

    def ping(self) -> None:
        with self.engine.connect() as conn:
            conn.execute(text("SELECT 1"))

    def describe(self) -> str:
        return self.engine.url.render_as_string(hide_password=True)
