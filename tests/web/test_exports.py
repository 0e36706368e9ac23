# ruff: noqa: F811  (pytest fixtures imported by name, then requested by name)
"""Dashboard downloads: written by a child process in bounded memory, the same as the library's
tables; ``since`` as in ``emogen study export``."""

from __future__ import annotations

import io
import os
from typing import Any

import pandas as pd
from fastapi.testclient import TestClient

from emogen.study.export import export_tables
from tests.study.drive import command, new_key, run_to_end
from tests.web.study_app import RESEARCHER_TOKEN, app, client, db_url, pg_cluster  # noqa: F401

AUTH = {"Authorization": f"Bearer {RESEARCHER_TOKEN}"}


def test_dashboard_csv_is_the_export_table(client: TestClient, app: Any) -> None:
    token = client.post("/api/sessions", json={"participant_id": "D-1"}).json()["token"]
    state = client.post(f"/api/s/{token}/step", json={"command": "begin", "key": new_key()}).json()
    run_to_end(
        state,
        lambda kind, body: client.post(f"/api/s/{token}/step", json=command(kind, body)).json(),
    )
    whole = export_tables(app.state.store)
    for table in ("faces", "selections", "sessions"):
        r = client.get(f"/api/researcher/export/{table}.csv", headers=AUTH)
        assert r.status_code == 200 and r.headers["content-type"].startswith("text/csv")
        assert r.headers["content-disposition"] == f'attachment; filename="{table}.csv"'
        got = pd.read_csv(io.StringIO(r.text))
        assert list(got.columns) == list(whole[table].columns)
        assert len(got) == len(whole[table]) > 0
    faces = pd.read_csv(
        io.StringIO(client.get("/api/researcher/export/faces.csv", headers=AUTH).text)
    )
    w = [c for c in faces.columns if c.startswith("w_")]
    pd.testing.assert_frame_equal(faces[w], whole["faces"][w], check_dtype=False)
    # incremental: the session completed less than a minute ago is not in it yet
    r = client.get("/api/researcher/export/sessions.csv?since=2000-01-01", headers=AUTH)
    assert r.status_code == 200 and len(pd.read_csv(io.StringIO(r.text))) == 0
    r = client.get("/api/researcher/export/sessions.csv?since=soon", headers=AUTH)
    assert r.status_code == 422 and "'soon'" in r.json()["detail"]
    leftovers = [n for n in os.listdir("/tmp") if n.startswith("emogen-download-")]
    assert leftovers == []  # each download's folder is removed once sent
