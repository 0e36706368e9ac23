# ruff: noqa: F811  (pytest fixtures imported by name, then requested by name)
"""A full disk or a read-only database is said as such (issue 33): 503 naming it (not "busy"),
``/healthz`` failing until a write succeeds again, and one clear line at start.

SQLite's own limits stand in for the disk: ``max_page_count`` at the file's size fails a write
with SQLITE_FULL ("database or disk is full"), ``query_only`` with SQLITE_READONLY; PostgreSQL is
made read-only with ``default_transaction_read_only``."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pytest
from fastapi.testclient import TestClient
from sqlalchemy import event, text

from emogen.errors import ResourceError
from emogen.study.storage import Store
from tests.study.drive import new_key
from tests.web.study_app import app, client, db_url, pg_cluster  # noqa: F401


def on_connect(store: Store, pragma: Callable[[Any], None]) -> Callable[[], None]:
    """Run ``pragma(dbapi_connection)`` on every new connection of the store; returns undo."""

    def listener(dbapi_conn: Any, _record: Any) -> None:
        pragma(dbapi_conn)

    event.listen(store.engine, "connect", listener)
    store.engine.dispose()  # pooled connections are made again, with it

    def undo() -> None:
        event.remove(store.engine, "connect", listener)
        store.engine.dispose()

    return undo


def read_only(store: Store) -> Callable[[], None]:
    if store.is_sqlite:
        return on_connect(store, lambda c: c.execute("PRAGMA query_only=ON"))
    name = store.engine.url.database

    def alter(value: str) -> None:
        with store.engine.connect().execution_options(isolation_level="AUTOCOMMIT") as conn:
            conn.execute(text("SET default_transaction_read_only = off"))  # this session writes
            conn.execute(
                text(f'ALTER DATABASE "{name}" SET default_transaction_read_only = {value}')
            )
        store.engine.dispose()

    alter("on")
    return lambda: alter("off")


@pytest.mark.parametrize("db_url", ["sqlite"], indirect=True)  # SQLite's max_page_count
def test_a_full_disk_is_503_naming_it_and_healthz_fails(app: Any, client: TestClient) -> None:
    store = app.state.store
    assert client.get("/healthz").status_code == 200

    def full(conn: Any) -> None:
        pages = conn.execute("PRAGMA page_count").fetchone()[0]
        conn.execute(f"PRAGMA max_page_count={pages}")

    undo = on_connect(store, full)
    answers = [client.post("/api/sessions", json={"participant_id": f"F-{i}"}) for i in range(40)]
    refused = [r for r in answers if r.status_code != 201]
    assert refused, "the writes should have met the full file"
    assert all(r.status_code == 503 for r in refused)
    assert "disk of the study database is full" in refused[0].json()["detail"]
    health = client.get("/healthz")
    assert health.status_code == 503 and "full" in health.json()["problem"]
    undo()  # space again: the next write succeeds and /healthz recovers
    assert client.post("/api/sessions", json={"participant_id": "F-ok"}).status_code == 201
    assert client.get("/healthz").status_code == 200


def test_a_read_only_database_is_503_naming_it(app: Any, client: TestClient) -> None:
    token = client.post("/api/sessions", json={"participant_id": "RO-1"}).json()["token"]
    undo = read_only(app.state.store)
    try:
        r = client.post(f"/api/s/{token}/step", json={"command": "begin", "key": new_key()})
        assert r.status_code == 503 and "read-only" in r.json()["detail"], r.text
        health = client.get("/healthz")
        assert health.status_code == 503 and "read-only" in health.json()["problem"]
    finally:
        undo()
    assert (
        client.post(f"/api/s/{token}/step", json={"command": "begin", "key": new_key()}).status_code
        == 200
    )
    assert client.get("/healthz").status_code == 200


def test_a_read_only_database_is_refused_at_start(db_url: str, ict_model: Any) -> None:
    from emogen.study.config import study_from_dict
    from emogen.web import create_app
    from tests.study.conftest import SMALL_STUDY

    store = Store(db_url)  # the database exists (and is current) …
    undo = read_only(store)  # … but cannot be written
    listener_store = store
    try:
        if store.is_sqlite:  # every engine on the file: the server opens its own
            pragma = lambda c, _r: c.execute("PRAGMA query_only=ON")  # noqa: E731
            event.listen(type(store.engine), "connect", pragma)
        with pytest.raises(ResourceError, match=r"cannot save anything in .*read-only"):
            create_app(study_from_dict(SMALL_STUDY), db_url, model=ict_model)
    finally:
        if store.is_sqlite:
            event.remove(type(store.engine), "connect", pragma)
        undo()
        listener_store.dispose()
