# ruff: noqa: F811  (pytest fixtures imported by name, then requested by name)
"""The study API over HTTP (both backends): a whole session, and every kind of bad request."""

from __future__ import annotations

from typing import Any

import pytest
from fastapi.testclient import TestClient
from sqlalchemy import func, select

from emogen.correct import correct_faces, model_correctives
from emogen.study.tables import FaceRow, PopulationRow, SelectionRow, StepRow
from tests.study.drive import choose, new_key, run_to_end, step_args
from tests.web.study_app import RESEARCHER_TOKEN, app, client, db_url, pg_cluster  # noqa: F401

AUTH = {"Authorization": f"Bearer {RESEARCHER_TOKEN}"}


def start(client: TestClient, participant: str | None) -> tuple[str, dict[str, Any]]:
    r = client.post("/api/sessions", json={"participant_id": participant})
    assert r.status_code == 201, r.text
    body = r.json()
    assert body["url"] == f"/s/{body['token']}"
    return body["token"], body["state"]


def http_caller(client: TestClient, token: str):  # type: ignore[no-untyped-def]
    def call(kind: str, body: dict[str, Any]) -> dict[str, Any]:
        r = client.post(f"/api/s/{token}/{kind}", json=body)
        assert r.status_code == 200, r.text
        assert r.headers["server-timing"].startswith("app;dur=")
        return r.json()  # type: ignore[no-any-return]

    return call


def counts(app: Any) -> tuple[int, ...]:
    with app.state.store.read() as db:
        return tuple(
            int(db.scalar(select(func.count()).select_from(t)) or 0)
            for t in (PopulationRow, FaceRow, SelectionRow, StepRow)
        )


def test_pages_and_whole_session_over_http(client: TestClient) -> None:
    page = client.get("/?PROLIFIC_PID=abc")
    assert page.status_code == 200 and "I agree" in page.text
    token, state = start(client, "H-1")
    page = client.get(f"/s/{token}")
    assert page.status_code == 200 and f'data-token="{token}"' in page.text
    assert client.get(f"/api/s/{token}/state").json() == state
    final = run_to_end(state, http_caller(client, token))
    assert final["stage"] == "done" and final["completion"]["code"] == "DONE-42"
    assert client.get("/researcher").status_code == 200
    assert client.get("/static/session.js").status_code == 200


def test_bad_requests_get_4xx_with_a_clear_message(client: TestClient, app: Any) -> None:
    token, _ = start(client, "H-2")
    other, _ = start(client, "H-3")
    state = client.post(f"/api/s/{token}/begin", json={"key": new_key()}).json()
    elite, others = choose(state)
    good = {"key": new_key(), **step_args(state), "elite": elite, "others": others}
    before = counts(app)
    url = f"/api/s/{token}/select"
    cases: list[tuple[str, Any, int, str]] = [
        # (url, body, status, text in the message)
        (url, "not json", 422, "invalid request"),
        (url, {**good, "elite": "3"}, 422, "elite: Input should be a valid integer; got '3'"),
        (url, {**good, "elite": -1}, 422, "got -1"),
        (url, {**good, "elite": 2**40}, 422, "elite"),
        (url, {**good, "others": [1.5]}, 422, "others"),
        (url, {**good, "key": "short"}, 422, "key"),
        (url, {**good, "extra": 1}, 422, "extra"),
        (url, {**good, "response_ms": -5}, 422, "response_ms"),
        (url, {**good, "key": "k" * 500}, 422, "got 'kkkkk"),
        (url, {k: v for k, v in good.items() if k != "elite"}, 422, "elite"),
        (url, {**good, "elite": 999}, 422, "not in the population"),
        (url, {**good, "others": list(range(100))}, 422, "not in the population"),
        (url, {**good, "generation": 5}, 409, "reload the page"),
        (url, {**good, "trial": 1}, 409, "trial 2"),
        (f"/api/s/{other}/select", good, 409, "not in a trial"),  # another session's step
        (f"/api/s/{'z' * 32}/select", good, 404, "no session"),
        ("/api/s/short/select", good, 422, "token"),
        (f"/api/s/{token}/rating", {"key": new_key(), "trial": 0, "value": 9}, 409, "rating"),
        (f"/api/s/{token}/rating", {"key": new_key(), "trial": 0, "value": 0}, 422, "value"),
        (f"/api/s/{token}/begin", {"key": new_key()}, 409, "past the instructions"),
        ("/api/sessions", {"participant_id": "has spaces"}, 422, "participant id"),
        ("/api/sessions", {"participant_id": "H-2"}, 409, "already has a session"),
        ("/api/sessions", {"participant_id": "x" * 500}, 422, "participant_id"),
    ]
    for path, body, status, text in cases:
        if isinstance(body, str):
            r = client.post(path, content=body, headers={"Content-Type": "application/json"})
        else:
            r = client.post(path, json=body)
        assert r.status_code == status, (path, body, r.status_code, r.text)
        assert text in r.json()["detail"], (path, body, r.json())
    assert counts(app) == before  # nothing half-done
    # the good request goes through once; replayed, it is the same step
    first = client.post(url, json=good)
    replay = client.post(url, json=good)
    assert first.status_code == replay.status_code == 200
    assert (
        replay.json().pop("replayed") is True
        and replay.json()["progress"] == first.json()["progress"]
    )
    stale = client.post(url, json={**good, "key": new_key()})
    assert stale.status_code == 409
    assert counts(app)[2] == before[2] + 1


def test_participants_cannot_reach_researcher_data(client: TestClient, app: Any) -> None:
    token, _ = start(client, "H-4")
    for path in ("/api/researcher/status", "/api/researcher/export/faces.csv"):
        r = client.get(path)
        assert r.status_code == 403 and "Authorization" in r.json()["detail"]
        r = client.get(path, headers={"Authorization": f"Bearer {token}"})
        assert r.status_code == 403
        assert client.get(path, headers=AUTH).status_code == 200
    status = client.get("/api/researcher/status", headers=AUTH).json()
    assert status["sessions"][0]["participant_id"] == "H-4"
    assert token not in str(status)  # tokens never leave the participant's own link
    csv = client.get("/api/researcher/export/sessions.csv", headers=AUTH).text
    assert "H-4" in csv and token not in csv
    assert client.get("/api/researcher/export/secrets.csv", headers=AUTH).status_code == 422
    # a participant's state holds only their own session
    state = client.get(f"/api/s/{token}/state").json()
    assert set(state) == {
        "stage",
        "participant_id",
        "progress",
        "limits",
        "allow_restart",
        "trial",
        "population",
        "rating",
        "categorise",
        "completion",
    }
    app.state.researcher_token = None
    r = client.get("/api/researcher/status", headers=AUTH)
    assert r.status_code == 403 and "EMOGEN_RESEARCHER_TOKEN" in r.json()["detail"]


@pytest.mark.parametrize("db_url", ["sqlite"], indirect=True)
def test_model_glb_and_face_images_are_scoped(client: TestClient) -> None:
    r = client.get("/api/model/alien.glb")
    assert r.status_code == 404 and "identity" in r.json()["detail"]
    token, _ = start(client, "H-5")
    r = client.get(f"/api/s/{token}/faces/0.png")
    assert r.status_code == 404  # no faces before the trial starts
    other, _ = start(client, "H-6")
    state = client.post(f"/api/s/{other}/begin", json={"key": new_key()}).json()
    face = state["population"]["faces"][0]["id"]
    assert client.get(f"/api/s/{token}/faces/{face}.png").status_code == 404


def test_shown_and_stored_faces_carry_their_correctives(
    client: TestClient, app: Any, ict_model
) -> None:  # type: ignore[no-untyped-def]
    """correct = true (the default): the shown vector is shapes then correctives, in the model
    GLB's target order, and the stored columns equal correct_faces(model, weights)."""
    import json

    import numpy as np

    from emogen.study.tables import StudyRow

    token, _ = start(client, "H-9")
    state = client.post(f"/api/s/{token}/begin", json={"key": new_key()}).json()
    faces = state["population"]["faces"]
    shown = np.array([f["weights"] for f in faces])
    n = ict_model.n_shapes
    result = correct_faces(ict_model, shown[:, :n])
    assert shown.shape[1] == n + len(result.corrective_names)
    np.testing.assert_array_equal(shown[:, :n], result.weights)  # effective = core for GA faces
    np.testing.assert_array_equal(shown[:, n:], result.correctives)
    with app.state.store.read() as db:
        stored = {
            f.face_id: json.loads(f.weights)
            for f in db.scalars(
                select(FaceRow).where(FaceRow.face_id.in_([f["id"] for f in faces]))
            )
        }
        names = json.loads(db.scalars(select(StudyRow)).first().weight_names)
    assert [stored[f["id"]] for f in faces] == shown.tolist()
    targets = [*ict_model.shape_names, *model_correctives(ict_model).names]
    assert names == targets == list(ict_model.shape_names) + list(result.corrective_names)
    # the viewer's GLB has one morph target per column, in the same order
    glb = client.get("/api/model/generic.glb")
    assert glb.status_code == 200
    size = int.from_bytes(glb.content[12:16], "little")
    doc = json.loads(glb.content[20 : 20 + size])
    assert doc["meshes"][0]["extras"]["targetNames"] == targets
    png = client.get(f"/api/s/{token}/faces/{faces[0]['id']}.png")
    assert png.status_code == 200 and png.content[:4] == b"\x89PNG"
