# ruff: noqa: F811  (pytest fixtures imported by name, then requested by name)
"""Bad inputs an attacker or a mistyped link sends: the answers the docs promise (issue 33).

``since`` outside the representable times is a 422 naming it (never a 500), participant ids are
matched whole (a trailing newline is no second participant), link errors are HTML pages, and a
face of an earlier generation is not served any more (404).
"""

from __future__ import annotations

from typing import Any

import pytest
from fastapi.testclient import TestClient

from emogen.errors import ConfigError
from emogen.study.enrolment import checked_participant
from emogen.study.export_stream import parse_since
from tests.study.drive import choose, command, new_key, run_to_end, step_args
from tests.web.study_app import RESEARCHER_TOKEN, app, client, db_url, pg_cluster  # noqa: F401

AUTH = {"Authorization": f"Bearer {RESEARCHER_TOKEN}"}
EDGES = ("9999-12-31T23:59:59-23:59", "0001-01-01T00:00:00+01:00")


@pytest.mark.parametrize("text", EDGES)
def test_since_outside_the_representable_times_is_named(text: str) -> None:
    with pytest.raises(ConfigError, match=r"--since .*between"):
        parse_since(text)


def test_since_outside_the_representable_times_is_a_422(client: TestClient) -> None:
    for text in EDGES:
        r = client.get("/api/researcher/export/sessions.csv", params={"since": text}, headers=AUTH)
        assert r.status_code == 422, r.text
        assert text in r.json()["detail"]


@pytest.mark.parametrize("bad", ["P001\n", "P001\r\n", "\nP001"])
def test_participant_ids_are_matched_whole(bad: str) -> None:
    with pytest.raises(ConfigError, match="participant id"):
        checked_participant(bad)


def test_a_trailing_newline_is_no_second_participant(client: TestClient) -> None:
    assert client.post("/api/sessions", json={"participant_id": "P001"}).status_code == 201
    r = client.post("/api/sessions", json={"participant_id": "P001\n"})
    assert r.status_code == 422 and "participant id" in r.json()["detail"]


@pytest.mark.parametrize(
    "path",
    [
        "/s/",
        "/s",
        "/S/abcdefghijklmnopqrstuvwxyz012345",
        "/s/abcdefghijklmnopqrstuvwxyz012345/x",
        "/s/a/b/c",
    ],
)
def test_link_errors_are_html_pages(client: TestClient, path: str) -> None:
    r = client.get(path, headers={"Accept": "text/html"})
    assert r.status_code == 404
    assert r.headers["content-type"].startswith("text/html"), r.text[:200]
    assert "This session link is not valid" in r.text


def test_api_errors_stay_json(client: TestClient) -> None:
    r = client.get("/api/nothing-here")
    assert r.status_code == 404 and r.headers["content-type"] == "application/json"


def test_faces_of_earlier_generations_are_not_served(client: TestClient) -> None:
    token = client.post("/api/sessions", json={"participant_id": "G-1"}).json()["token"]
    state: dict[str, Any] = client.post(
        f"/api/s/{token}/step", json={"command": "begin", "key": new_key()}
    ).json()
    first = [f["id"] for f in state["view"]["population"]["faces"]]
    where = {"trial": state["progress"]["trial"], "attempt": state["trial"]["attempt"]}
    assert client.get(f"/api/s/{token}/faces/{first[0]}.png", params=where).status_code == 200
    elite, others = choose(state)
    body = {"key": new_key(), **step_args(state), "elite": elite, "others": others}
    state = client.post(f"/api/s/{token}/step", json={"command": "select", **body}).json()
    assert state["view"]["generation"] == 1
    now = {f["id"] for f in state["view"]["population"]["faces"]}
    gone = [i for i in first if i not in now]
    assert gone, "generation 1 should have new faces"
    for face in gone:
        for params in (where, {}):
            r = client.get(f"/api/s/{token}/faces/{face}.png", params=params)
            assert r.status_code == 404, (face, params)
    shown = sorted(now)[0]
    assert client.get(f"/api/s/{token}/faces/{shown}.png", params=where).status_code == 200


def test_the_final_face_is_served_while_the_trial_waits_for_its_rating(client: TestClient) -> None:
    token = client.post("/api/sessions", json={"participant_id": "G-2"}).json()["token"]
    state: dict[str, Any] = client.post(
        f"/api/s/{token}/step", json={"command": "begin", "key": new_key()}
    ).json()
    state = run_to_end(
        state,
        lambda kind, body: client.post(f"/api/s/{token}/step", json=command(kind, body)).json(),
        stop=lambda s: s["stage"] == "trial" and s["trial"]["status"] == "rating",
    )
    final = state["view"]["rating"]["face"]["id"]
    where = {"trial": state["progress"]["trial"], "attempt": state["trial"]["attempt"]}
    assert client.get(f"/api/s/{token}/faces/{final}.png", params=where).status_code == 200
    others = [i for i in range(final + 1) if i != final][:3]
    for face in others:
        assert client.get(f"/api/s/{token}/faces/{face}.png", params=where).status_code == 404
