"""Alembic migrations of the study database, run programmatically when a Store opens.

A new migration: ``alembic -c /dev/null`` is not needed; write a file in ``versions/`` with
``revision``/``down_revision`` (see ``0001_initial.py``); ``upgrade`` runs every pending one.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from sqlalchemy import text

if TYPE_CHECKING:
    from alembic.config import Config
    from sqlalchemy.engine import Engine

HERE = Path(__file__).resolve().parent
#: The newest revision in ``versions/`` (a test checks it against Alembic's own head): a
#: database already there is opened without importing Alembic (~10 MB, ~0.1 s per process).
HEAD = "0005"
# Serialises concurrent upgrades on PostgreSQL (two servers starting at once).
_PG_LOCK_ID = 0x456D6F47656E  # "EmoGen"


def alembic_config() -> Config:
    from alembic.config import Config

    cfg = Config()
    cfg.set_main_option("script_location", str(HERE))
    return cfg


def upgrade(engine: Engine, revision: str = "head") -> None:
    """Bring the database's schema to ``revision`` (default: the newest).

    engine : the store's writing engine (``BEGIN IMMEDIATE`` on SQLite).
    """
    if revision in ("head", HEAD) and stored_revision(engine) == HEAD:
        return
    from alembic import command

    cfg = alembic_config()
    with engine.connect() as conn:
        sqlite = conn.dialect.name == "sqlite"
        raw: Any = conn.connection.driver_connection
        if sqlite:  # a table rebuild (batch migration) must not trip its children's keys
            raw.execute("PRAGMA foreign_keys=OFF")  # only outside a transaction
        try:
            with conn.begin():
                if conn.dialect.name == "postgresql":
                    conn.execute(text("SELECT pg_advisory_xact_lock(:k)"), {"k": _PG_LOCK_ID})
                cfg.attributes["connection"] = conn
                command.upgrade(cfg, revision)
                if sqlite:
                    broken = conn.exec_driver_sql("PRAGMA foreign_key_check").fetchall()
                    if broken:
                        raise RuntimeError(f"migration broke foreign keys: {broken[:5]}")
        finally:
            if sqlite:
                raw.execute("PRAGMA foreign_keys=ON")


def stored_revision(engine: Engine) -> str | None:
    """The revision in the ``alembic_version`` table, read with plain SQL (None: no table,
    no row, or more than one head)."""
    from sqlalchemy import inspect

    with engine.connect() as conn:
        if not inspect(conn).has_table("alembic_version"):
            return None
        rows = conn.execute(text("SELECT version_num FROM alembic_version")).fetchall()
    return str(rows[0][0]) if len(rows) == 1 else None


def current_revision(engine: Engine) -> str | None:
    """The database's schema revision (None before the first migration)."""
    from alembic.runtime.migration import MigrationContext

    with engine.connect() as conn:
        return MigrationContext.configure(conn).get_current_revision()
