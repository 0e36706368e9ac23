"""Database engines of the study store: SQLite (WAL, ``synchronous=FULL``, foreign keys; or
read-only, writing nothing, for commands that only read) and PostgreSQL."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from sqlalchemy import create_engine, event
from sqlalchemy.engine import Engine, make_url

from emogen.errors import ConfigError, ResourceError

DATABASE_ENV = "EMOGEN_DATABASE_URL"


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


def _sqlite_read_pragmas(dbapi_conn: Any, _record: Any) -> None:
    """A read-only connection: the journal mode left as the file has it (setting WAL writes)."""
    dbapi_conn.isolation_level = None
    cur = dbapi_conn.cursor()
    cur.execute("PRAGMA busy_timeout=30000")
    cur.close()


def _sqlite_begin(conn: Any) -> None:
    mode = conn.get_execution_options().get("sqlite_begin", "")
    conn.exec_driver_sql(f"BEGIN {mode}".strip())


def make_engine(url: str, *, create: bool = True) -> Engine:
    """An engine for ``url``; ``create=False`` (read-only commands) refuses an SQLite file that
    does not exist instead of creating it (and its folders)."""
    url = normalise_url(url)
    try:
        parsed = make_url(url)
    except Exception as exc:  # sqlalchemy.exc.ArgumentError
        raise ConfigError(f"database URL {url!r} is not valid: {exc}") from None
    if parsed.get_backend_name() == "sqlite":
        db = parsed.database
        if not db or db == ":memory:":
            raise ConfigError("database URL must name an SQLite file (':memory:' is not durable)")
        path = Path(db).expanduser()
        if not create and (not path.is_file() or path.stat().st_size == 0):
            what = "is an empty file, not a" if path.is_file() else "does not exist: no"
            raise ResourceError(
                f"{path} {what} study database: check --database-url (or ${DATABASE_ENV}, "
                "the study config's database_url); `emogen serve` creates it"
            )
        if not create:  # read it only: never a write, so a read-only copy (an archive) opens
            engine = create_engine(
                f"sqlite:///file:{path.resolve()}?mode=ro&uri=true",
                connect_args={"timeout": 30, "check_same_thread": False},
                pool_size=8,
            )
            event.listen(engine, "connect", _sqlite_read_pragmas)
            event.listen(engine, "begin", _sqlite_begin)
            return engine
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
