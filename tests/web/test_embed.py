"""Embedding the study in another site's page (issue #31, the jsPsych plugin's server side):
CORS for exactly the configured origins (none by default, no wildcard), the security headers
unchanged, the study's blocks and a trial's record (session id, seeds, final face) as the
database holds them."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from sqlalchemy import select

from emogen.errors import ConfigError
from emogen.study.config import study_from_dict
from emogen.study.tables import SessionRow, TrialRow
from emogen.tasks.evolve.tables import FaceRow, PopulationRow
from emogen.web.limits import CONTENT_SECURITY_POLICY
from tests.study.conftest import SMALL_STUDY
from tests.study.drive import command, run_to_end
from tests.web.test_security import make_app

SITE = "https://experiments.example.org"
PREFLIGHT = {
    "Access-Control-Request-Method": "POST",
    "Access-Control-Request-Headers": "content-type",
}


@pytest.fixture
def embedded(tmp_path: Path, ict_model: Any) -> Iterator[TestClient]:
    app = make_app(tmp_path, ict_model, study={**SMALL_STUDY, "embed_origins": [SITE]})
    with TestClient(app) as c:
        yield c


@pytest.fixture
def plain(tmp_path: Path, ict_model: Any) -> Iterator[TestClient]:
    with TestClient(make_app(tmp_path, ict_model, name="plain")) as c:
        yield c


def test_an_allowed_origin_gets_cors_headers_for_exactly_itself(embedded: TestClient) -> None:
    pre = embedded.options("/api/sessions", headers={"Origin": SITE, **PREFLIGHT})
    assert pre.status_code == 200
    assert pre.headers["access-control-allow-origin"] == SITE
    assert "POST" in pre.headers["access-control-allow-methods"]
    assert "access-control-allow-credentials" not in pre.headers
    made = embedded.post("/api/sessions", json={"participant_id": "p1"}, headers={"Origin": SITE})
    assert made.status_code == 201
    assert made.headers["access-control-allow-origin"] == SITE
    # the page may read a compressed download's encoding (its loading bar's total, #40)
    assert made.headers["access-control-expose-headers"] == "Content-Encoding"
    # the pages stay unframeable and script-strict, CORS or not
    assert made.headers["content-security-policy"] == CONTENT_SECURITY_POLICY
    assert "frame-ancestors 'none'" in made.headers["content-security-policy"]
    assert made.headers["x-frame-options"] == "DENY"
    assert pre.headers["x-frame-options"] == "DENY"


@pytest.mark.parametrize(
    "origin",
    [
        "https://evil.example.org",
        "https://experiments.example.org:8443",
        "http://experiments.example.org",
        "null",
    ],
)
def test_another_origin_gets_no_cors_headers(embedded: TestClient, origin: str) -> None:
    pre = embedded.options("/api/sessions", headers={"Origin": origin, **PREFLIGHT})
    assert pre.status_code == 400  # Starlette refuses the preflight
    assert "access-control-allow-origin" not in pre.headers
    got = embedded.get("/api/study", headers={"Origin": origin})
    assert "access-control-allow-origin" not in got.headers


def test_no_origin_is_allowed_by_default(plain: TestClient) -> None:
    pre = plain.options("/api/sessions", headers={"Origin": SITE, **PREFLIGHT})
    assert "access-control-allow-origin" not in pre.headers
    got = plain.get("/api/study", headers={"Origin": SITE})
    assert got.status_code == 200 and "access-control-allow-origin" not in got.headers


@pytest.mark.parametrize(
    ("origin", "words"),
    [
        ("*", "no wildcard"),
        ("https://*.example.org", "no wildcard"),
        ("https://example.org/", "no trailing '/'"),
        ("https://example.org/study", "no path"),
        ("ftp://example.org", "http or https"),
        ("example.org", "scheme://host"),
        ("http://localhost:70000", "port 70000"),
    ],
)
def test_embed_origins_must_be_exact_origins(origin: str, words: str) -> None:
    with pytest.raises(ConfigError, match="embed_origins") as err:
        study_from_dict({**SMALL_STUDY, "embed_origins": [origin]})
    assert words in str(err.value) and repr(origin) in str(err.value)


def test_embed_origins_leave_the_config_hash_alone() -> None:
    a = study_from_dict(SMALL_STUDY)
    b = study_from_dict({**SMALL_STUDY, "embed_origins": [SITE, "http://localhost:8000"]})
    assert b.embed_origins == (SITE, "http://localhost:8000")
    assert a.config_hash() == b.config_hash()  # existing sessions stay this study's


def test_study_info_names_the_blocks(embedded: TestClient) -> None:
    info = embedded.get("/api/study").json()
    assert info["name"] == "small"
    assert info["participant_param"] == "PROLIFIC_PID"
    assert info["framing"] == "face"
    # what its trials show (the config's: two emotions, the default identity, ga.generations, ten faces a generation,
    # the selection's limits, the rating's default scale), nothing a participant may not know
    shows = {
        "emotions": ["happy", "sad"],
        "identities": ["generic"],
        "generations": 2,
        "faces": 10,
        "min_selections": 1,
        "max_selections": 4,
        "rating_points": 7,
    }
    assert info["blocks"] == [
        {"block": 0, "name": "block1", "task": "evolve", "trials": 2, "shows": shows}
    ]
    assert len(info["weight_names"]) > 50 and info["weight_names"][0] != ""


def before_emotion(client: TestClient, token: str) -> str:
    """The emotion trial 0 asks for, as the database holds it."""
    store = client.app.state.store  # type: ignore[attr-defined]
    with store.read() as db:
        sess = db.scalar(select(SessionRow).where(SessionRow.token == token))
        first = (TrialRow.session_id == sess.id, TrialRow.position == 0)
        return str(db.scalar(select(TrialRow.emotion).where(*first)))


def test_trial_record_is_what_the_database_holds(embedded: TestClient) -> None:
    made = embedded.post("/api/sessions", json={"participant_id": "rec-1"}).json()
    token = made["token"]
    before = embedded.get(f"/api/s/{token}/trials/0").json()
    emotion = before_emotion(embedded, token)
    assert before["result"] == {"task": "evolve", "emotion": emotion, "final_face": None}
    assert before["status"] == "pending"

    def post(kind: str, body: dict[str, Any]) -> dict[str, Any]:
        r = embedded.post(f"/api/s/{token}/step", json=command(kind, body))
        assert r.status_code == 200, r.text
        return r.json()  # type: ignore[no-any-return]

    run_to_end(made["state"], post)
    store = embedded.app.state.store  # type: ignore[attr-defined]
    with store.read() as db:
        sess = db.scalar(select(SessionRow).where(SessionRow.token == token))
        trials = db.scalars(select(TrialRow).where(TrialRow.session_id == sess.id)).all()
        for t in trials:
            got = embedded.get(f"/api/s/{token}/trials/{t.position}").json()
            face = db.scalar(
                select(FaceRow)
                .join(PopulationRow, FaceRow.population_id == PopulationRow.id)
                .where(
                    PopulationRow.trial_id == t.id,
                    PopulationRow.attempt == t.attempt,
                    FaceRow.face_id == t.final_face_id,
                )
            )
            assert got["session_id"] == sess.id and got["participant_id"] == "rec-1"
            assert got["seed"] == str(t.seed) and got["session_seed"] == str(sess.seed)
            assert int(got["seed"]) == t.seed  # exact, past 2**53
            assert got["status"] == "done" and got["task"] == "evolve"
            assert got["block_name"] == "block1" and "emotion" not in got
            final = {"id": face.face_id, "weights": json.loads(face.weights)}
            assert got["result"] == {"task": "evolve", "emotion": t.emotion, "final_face": final}
    assert embedded.get(f"/api/s/{token}/trials/9").status_code == 404
    assert embedded.get(f"/api/s/{'x' * 20}/trials/0").status_code == 404


def test_study_info_says_the_framing(tmp_path: Path, ict_model: Any) -> None:
    """The jsPsych plugin shows the faces in the study's framing: it reads it here."""
    app = make_app(tmp_path, ict_model, study={**SMALL_STUDY, "framing": "oval"})
    with TestClient(app) as client:
        assert client.get("/api/study").json()["framing"] == "oval"


def test_a_simulated_session_is_marked_so_in_the_database(embedded: TestClient) -> None:
    """The plugin's visual simulate() makes its sessions with ``simulated: true`` (#40): they
    are ``participant_source = "simulated"``; a participant's stays ``url``."""
    for pid, simulated in (("pilot-1", True), ("real-1", False)):
        made = embedded.post("/api/sessions", json={"participant_id": pid, "simulated": simulated})
        assert made.status_code == 201
    store = embedded.app.state.service.store  # type: ignore[attr-defined]
    with store.read() as db:
        rows = db.execute(select(SessionRow.participant_id, SessionRow.participant_source)).all()
    assert sorted(rows) == [("pilot-1", "simulated"), ("real-1", "url")]
