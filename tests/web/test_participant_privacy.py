"""Nothing a participant should not see (issue #38): while a categorise trial waits for its
answer, no participant endpoint — the state, a step's answer (and its replay), the trial
records of every trial, the study's info, the session page, a resumed session — says the
emotion the face was made for, nor whose face it is (its source, the session, participant or
trial it was made in)."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from sqlalchemy import select

from emogen.study.tables import TrialRow
from emogen.tasks.categorise.tables import StimulusRow
from tests.study.drive import command, new_key, run_to_end
from tests.web.test_security import make_app

LABELS = ["happy", "sad", "angry"]
STUDY: dict[str, Any] = {
    "name": "private",
    "seed": 9,
    "emotions": LABELS,
    "order": "fixed",
    "ga": {"generations": 1, "min_selections": 1, "max_selections": 3},
    "blocks": [
        {"task": "evolve"},
        {"task": "categorise", "own": True, "others": 2, "intensity": True},
    ],
}
#: Keys that would say what a face was made for, or whose it is.
SECRET_KEYS = {"emotion", "intended", "source", "source_session_id", "source_trial",
               "source_face_id", "source_row", "source_label", "fallback", "session_id"}  # fmt: skip


@pytest.fixture
def client(tmp_path: Path, ict_model: Any) -> Iterator[TestClient]:
    with TestClient(make_app(tmp_path, ict_model, study=STUDY, name="private")) as c:
        yield c


def keys(value: Any) -> set[str]:
    """Every key of a JSON value, at any depth."""
    if isinstance(value, dict):
        return set(value) | {k for v in value.values() for k in keys(v)}
    if isinstance(value, list):
        return {k for v in value for k in keys(v)}
    return set()


def step(client: TestClient, token: str) -> Any:
    def call(kind: str, body: dict[str, Any]) -> Any:
        r = client.post(f"/api/s/{token}/step", json=command(kind, body))
        assert r.status_code == 200, r.text
        return r.json()

    return call


def test_no_participant_endpoint_tells_a_categorised_face_s_making(client: TestClient) -> None:
    first = client.post("/api/sessions", json={"participant_id": "maker-1"}).json()
    run_to_end(first["state"], step(client, first["token"]))  # faces for others to label
    made = client.post("/api/sessions", json={"participant_id": "judge-1"}).json()
    token = made["token"]
    state = run_to_end(
        made["state"],
        step(client, token),
        stop=lambda s: s["stage"] == "trial" and s["trial"]["task"] == "categorise",
    )
    own_id = client.get(f"/api/s/{token}/trials/0").json()["session_id"]
    store = client.app.state.store  # type: ignore[attr-defined]
    with store.read() as db:  # what the server knows of the faces this session will label
        stims = db.execute(
            select(StimulusRow.source, StimulusRow.intended)
            .join(TrialRow, TrialRow.id == StimulusRow.trial_id)
            .where(TrialRow.session_id == own_id)
        ).all()
    assert {s.source for s in stims} == {"own", "other"}  # both kinds are being labelled
    assert all(s.intended in LABELS for s in stims)
    key = new_key()
    answer = {"key": key, "trial": state["progress"]["trial"], "label": "happy", "intensity": 4}
    bodies = {
        "state": client.get(f"/api/s/{token}/state").json(),
        "study": client.get("/api/study").json(),
        "resumed": client.post(
            "/api/sessions", json={"participant_id": "judge-1", "resume_token": token}
        ).json(),
        **{
            f"trial {n}": client.get(f"/api/s/{token}/trials/{n}").json()
            for n in range(state["progress"]["trials"])
        },
    }
    current = bodies[f"trial {state['progress']['trial']}"]
    assert current["task"] == "categorise" and current["result"] is None  # not answered yet
    for name, body in bodies.items():
        allowed = {"session_id"} if name.startswith("trial") else set()  # their own session
        if body.get("task") == "evolve":
            allowed.add("emotion")  # the emotion they were asked to make
        leaked = keys(body) - allowed
        assert not leaked & SECRET_KEYS, (name, leaked & SECRET_KEYS)
        assert "maker-1" not in json.dumps(body), name  # whose face it is
    view = bodies["state"]["view"]
    assert view["task"] == "categorise" and set(view) == {
        "task",
        "question",
        "face",
        "labels",
        "none_option",
        "intensity",
        "confidence",
    }
    page = client.get(f"/s/{token}").text
    assert "maker-1" not in page and "intended" not in page
    after = client.post(f"/api/s/{token}/step", json=command("answer", answer)).json()
    again = client.post(f"/api/s/{token}/step", json=command("answer", answer)).json()
    assert again.pop("replayed") is True
    for body in (after, again):
        assert not keys(body) & SECRET_KEYS and "maker-1" not in json.dumps(body)
    answered = client.get(f"/api/s/{token}/trials/{answer['trial']}").json()["result"]
    assert set(answered) == {"task", "label", "weights"} and answered["label"] == "happy"
