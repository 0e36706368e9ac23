"""The researcher dashboard's API (issue #32): durations, progress per condition, Latin-square
row counts, every table in CSV and Parquet, the export's session numbering; a study that
requires a participant id, and the warning when the links never carry it."""

from __future__ import annotations

import io
import logging
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pandas as pd
import pytest
from fastapi.testclient import TestClient

from emogen.study.check import NEVER_MATCHED_AFTER
from emogen.study.config import study_from_dict
from emogen.study.export import TABLES, export_tables
from emogen.web.ratelimit import RateLimit
from tests.study.conftest import SMALL_STUDY
from tests.study.drive import command, new_key, run_to_end

TOKEN = "researcher-secret-0123456789-abcdefghij"
AUTH = {"Authorization": f"Bearer {TOKEN}"}
LATIN = {
    **SMALL_STUDY,
    "identities": ["female-light", "male-dark"],
    "order": "latin_square",
    "counterbalance": "arrival",
}


def _client(tmp_path: Path, model: Any, study: dict[str, Any]) -> TestClient:
    from emogen.web import create_app

    app = create_app(
        study_from_dict(study),
        f"sqlite:///{tmp_path / 'dash.sqlite'}",
        model=model,
        researcher_token=TOKEN,
        session_limit=RateLimit.parse("off"),
    )
    return TestClient(app)


@pytest.fixture
def latin(tmp_path: Path, ict_model: Any) -> Iterator[TestClient]:
    with _client(tmp_path, ict_model, LATIN) as c:
        yield c


def _start(client: TestClient, pid: str | None) -> str:
    token = client.post("/api/sessions", json={"participant_id": pid}).json()["token"]
    return str(token)


def _finish(client: TestClient, token: str) -> None:
    state = client.post(f"/api/s/{token}/step", json={"command": "begin", "key": new_key()}).json()
    run_to_end(
        state,
        lambda kind, body: client.post(f"/api/s/{token}/step", json=command(kind, body)).json(),
    )


def test_status_has_durations_conditions_rows_and_the_exports_numbers(latin: TestClient) -> None:
    tokens = [_start(latin, f"D-{k}") for k in range(3)]
    _finish(latin, tokens[0])
    _finish(latin, tokens[2])
    latin.post(f"/api/s/{tokens[1]}/step", json={"command": "begin", "key": new_key()})
    status = latin.get("/api/researcher/status", headers=AUTH).json()
    tables = export_tables(latin.app.state.store)
    sessions, trials = tables["sessions"], tables["trials"]
    # numbering: the dashboard's session_id and session_number are the export's
    shown = {
        s["participant_id"]: (s["session_id"], s["session_number"]) for s in status["sessions"]
    }
    exported = {
        p: (int(i), int(n))
        for p, i, n in zip(
            sessions["participant_id"],
            sessions["session_id"],
            sessions["session_number"],
            strict=True,
        )
    }
    assert shown == exported and sorted(n for _, n in shown.values()) == [0, 1, 2]
    # durations: consent → completion of the completed sessions, as the export's times say
    done = sessions[sessions["stage"] == "done"]
    minutes = pd.to_datetime(done["completed_at"]) - pd.to_datetime(done["consented_at"])
    median = minutes.dt.total_seconds().median() / 60
    assert status["durations"]["completed"] == 2
    assert status["durations"]["median_min"] == pytest.approx(median, abs=0.01)
    low, high = status["estimate"]["minutes"]
    assert 1 <= low <= high and "selection screens" in status["estimate"]["basis"]
    # per-condition progress: a plain count of the export's trials table
    for line in status["conditions"]:
        mine = trials[
            (trials["emotion"] == line["emotion"]) & (trials["identity"] == line["identity"])
        ]
        assert line["assigned"] == len(mine) == 3
        assert line["done"] == int((mine["status"] == "done").sum()) >= 2
    # 2 emotions × 2 identities, in the config's order
    assert [(c["emotion"], c["identity"]) for c in status["conditions"]] == [
        ("happy", "female-light"),
        ("happy", "male-dark"),
        ("sad", "female-light"),
        ("sad", "male-dark"),
    ]
    # Latin-square rows: exact, in arrival order (4 conditions: 4 rows)
    rows = status["counterbalancing"]
    assert rows["counterbalance"] == "arrival"
    assert [r["sessions"] for r in rows["rows"]] == [1, 1, 1, 0]
    assert [r["done"] for r in rows["rows"]] == [1, 0, 1, 0]
    assert status["warnings"] == []


def test_every_table_downloads_as_csv_and_parquet(latin: TestClient) -> None:
    _finish(latin, _start(latin, "T-1"))
    whole = export_tables(latin.app.state.store)
    page = latin.get("/researcher").text
    for table in TABLES:  # the page offers every table in both formats
        assert f'data-table="{table}" data-format="csv"' in page
        assert f'data-table="{table}" data-format="parquet"' in page
    for table in ("identities", "study", "sessions"):
        r = latin.get(f"/api/researcher/export/{table}.parquet", headers=AUTH)
        assert r.status_code == 200, r.text
        assert r.headers["content-disposition"] == f'attachment; filename="{table}.parquet"'
        got = pd.read_parquet(io.BytesIO(r.content))
        assert list(got.columns) == list(whole[table].columns) and len(got) == len(whole[table])
        r = latin.get(f"/api/researcher/export/{table}.csv", headers=AUTH)
        assert r.status_code == 200 and len(pd.read_csv(io.StringIO(r.text))) == len(whole[table])
    identities = pd.read_parquet(
        io.BytesIO(latin.get("/api/researcher/export/identities.parquet", headers=AUTH).content)
    )
    assert sorted(identities["identity"]) == ["female-light", "male-dark"]
    assert latin.get("/api/researcher/export/faces.xlsx", headers=AUTH).status_code == 404


def test_participant_required_refuses_links_without_the_id(tmp_path: Path, ict_model: Any) -> None:
    study = {**SMALL_STUDY, "participant_required": True}
    with _client(tmp_path, ict_model, study) as c:
        page = c.get("/")
        assert page.status_code == 400 and "Your participant id is missing" in page.text
        assert "?PROLIFIC_PID=YOUR_ID" in page.text and "I agree" not in page.text
        assert c.get("/?PROLIFIC_PID=R-1").status_code == 200
        assert c.get("/?participant=R-1").status_code == 200
        r = c.post("/api/sessions", json={"participant_id": None})
        assert (
            r.status_code == 400 and "needs your participant id in the link" in r.json()["detail"]
        )
        assert c.post("/api/sessions", json={"participant_id": "R-1"}).status_code == 201
    with _client(tmp_path, ict_model, {**SMALL_STUDY, "name": "anon"}) as c:  # the default
        assert c.get("/").status_code == 200
        assert c.post("/api/sessions", json={"participant_id": None}).status_code == 201


def test_a_parameter_no_link_carries_is_warned_about(
    tmp_path: Path, ict_model: Any, caplog: pytest.LogCaptureFixture
) -> None:
    # before: ?prolific_pid= for PROLIFIC_PID made every participant anonymous, silently
    with _client(tmp_path, ict_model, SMALL_STUDY) as c, caplog.at_level(logging.WARNING):
        for k in range(NEVER_MATCHED_AFTER):
            assert c.get(f"/?prolific_pid=PP-{k}").status_code == 200
            assert "the links came with" not in caplog.text
            _start(c, None)  # the page found no PROLIFIC_PID: an anonymous session
        warnings = c.get("/api/researcher/status", headers=AUTH).json()["warnings"]
        assert len(warnings) == 1 and f"none of the {NEVER_MATCHED_AFTER} sessions" in warnings[0]
        assert "the links came with ?prolific_pid=, not ?PROLIFIC_PID=" in warnings[0]
        logged = [r for r in caplog.records if "the links came with" in r.getMessage()]
        assert len(logged) == 1  # once
        _start(c, None)
        assert len([r for r in caplog.records if "the links came with" in r.getMessage()]) == 1
        _start(c, "GOOD-1")  # one link with the id: no warning any more
        assert c.get("/api/researcher/status", headers=AUTH).json()["warnings"] == []
