# ruff: noqa: F811  (pytest fixtures imported by name, then requested by name)
"""Fault test: the server (a uvicorn subprocess) is killed with SIGKILL mid-session and restarted.

The participant resumes at the same generation with the same faces; a request in flight at the
kill, retried with its idempotency key, is done exactly once; the export then holds each
generation once and replay regenerates every face. With one worker process and with two (the
server and its workers killed at once); with two, the same step sent many times at once is
stored once, whichever worker takes it.
"""

from __future__ import annotations

import contextlib
import threading
import time
from pathlib import Path
from typing import Any

import httpx
import pytest
from benchmarks.bench_study import ServerProcess, write_study_toml

from emogen.study.export import export_tables
from emogen.study.replay import replay_session
from emogen.study.storage import Store
from tests.study.conftest import SMALL_STUDY
from tests.study.drive import categorise_body, choose, command, new_key, run_to_end, step_args
from tests.study_fixtures import db_url, pg_cluster  # noqa: F401

pytestmark = pytest.mark.slow


def post(url: str, path: str, body: dict[str, Any]) -> dict[str, Any]:
    r = httpx.post(url + path, json=body, timeout=30)
    assert r.status_code in (200, 201), r.text
    return r.json()  # type: ignore[no-any-return]


def kill_with_step_in_flight(server: ServerProcess, path: str, body: dict[str, Any]) -> None:
    """SIGKILL the server 5 ms after sending a step (whose answer is then lost), and start it
    again."""

    def send() -> None:
        with contextlib.suppress(httpx.HTTPError):  # the server dies under it
            httpx.post(f"{server.url}{path}", json=body, timeout=5)

    in_flight = threading.Thread(target=send, daemon=True)
    in_flight.start()
    time.sleep(0.005)
    server.kill()
    in_flight.join(10)
    server.start()


@pytest.mark.parametrize("workers", [1, 2])
def test_sigkill_mid_session_loses_and_duplicates_nothing(
    db_url: str, tmp_path: Path, ict_dir: Path, ict_model, workers: int
) -> None:
    config = write_study_toml(SMALL_STUDY, tmp_path / "study.toml")
    server = ServerProcess(config, db_url, ict_dir, tmp_path / "server.log", workers).start()
    assert server.ready_workers() == workers
    try:
        created = post(server.url, "/api/sessions", {"participant_id": "K-1"})
        token = created["token"]
        state = post(server.url, f"/api/s/{token}/step", {"command": "begin", "key": new_key()})
        elite, others = choose(state)
        state = post(
            server.url,
            f"/api/s/{token}/step",
            {
                "command": "select",
                "key": new_key(),
                **step_args(state),
                "elite": elite,
                "others": others,
            },
        )
        assert state["view"]["generation"] == 1

        # 1. killed between steps: everything answered was committed
        server.kill()
        server.start()
        resumed = httpx.get(f"{server.url}/api/s/{token}/state", timeout=30).json()
        assert resumed == state  # same trial, generation, attempt and the very same faces

        # 2. killed with a step in flight: the retry (same key) is done exactly once
        elite, others = choose(state)
        body = {"key": new_key(), **step_args(state), "elite": elite, "others": others}

        kill_with_step_in_flight(server, f"/api/s/{token}/step", {"command": "select", **body})
        before = httpx.get(f"{server.url}/api/s/{token}/state", timeout=30).json()
        assert before["view"]["generation"] in (1, 2)  # the step happened wholly or not at all
        after = post(server.url, f"/api/s/{token}/step", {"command": "select", **body})
        assert after["view"]["generation"] == 2
        assert after.get("replayed", False) == (before["view"]["generation"] == 2)
        final = run_to_end(
            after,
            lambda kind, b: post(server.url, f"/api/s/{token}/step", command(kind, b)),
        )
        assert final["stage"] == "done"
    finally:
        server.stop()

    store = Store(db_url)
    tables = export_tables(store)
    faces, sel = tables["faces"], tables["selections"]
    per_generation = faces.groupby(["trial", "attempt", "generation"]).size()
    assert len(per_generation) == 6 and (per_generation == 10).all()
    elites = sel[sel.role == "elite"]
    assert len(elites) == 6 and not elites.duplicated(["trial", "attempt", "generation"]).any()
    assert len(tables["evolve_ratings"]) == 2
    report = replay_session(store, 1, ict_model.rig, ict_model.model_hash, model=ict_model)
    assert report.ok, report.mismatches
    store.dispose()


def test_the_same_step_sent_at_once_to_two_workers_is_stored_once(
    db_url: str, tmp_path: Path, ict_dir: Path
) -> None:
    config = write_study_toml(SMALL_STUDY, tmp_path / "study.toml")
    server = ServerProcess(config, db_url, ict_dir, tmp_path / "server.log", workers=2).start()
    try:
        assert server.ready_workers() == 2
        token = post(server.url, "/api/sessions", {"participant_id": "K-2"})["token"]
        state = post(server.url, f"/api/s/{token}/step", {"command": "begin", "key": new_key()})
        elite, others = choose(state)
        body = {"key": new_key(), **step_args(state), "elite": elite, "others": others}
        barrier = threading.Barrier(8)
        answers: list[dict[str, Any]] = []

        def send() -> None:
            with httpx.Client(timeout=60) as client:  # a connection of its own
                barrier.wait()
                r = client.post(
                    f"{server.url}/api/s/{token}/step", json={"command": "select", **body}
                )
                answers.append({"status": r.status_code, **r.json()})

        threads = [threading.Thread(target=send) for _ in range(8)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(120)
    finally:
        server.stop()
    assert [a["status"] for a in answers] == [200] * 8
    assert sorted(a.get("replayed", False) for a in answers) == [False] + [True] * 7
    assert len({str(a["view"]["population"]) for a in answers}) == 1
    store = Store(db_url)
    tables = export_tables(store)
    store.dispose()
    assert len(tables["selections"].query("role == 'elite'")) == 1
    per_generation = tables["faces"].groupby("generation").size()
    assert per_generation.to_dict() == {0: 10, 1: 10}


MIXED_STUDY = {
    **SMALL_STUDY,
    "name": "mixed-fault",
    "blocks": [
        {"task": "evolve"},
        {"task": "categorise", "own": True, "random": 2, "intensity": True},
    ],
}


@pytest.mark.parametrize("workers", [1, 2])
def test_sigkill_during_categorisation_loses_and_duplicates_nothing(
    db_url: str, tmp_path: Path, ict_dir: Path, ict_model, workers: int
) -> None:
    config = write_study_toml(MIXED_STUDY, tmp_path / "study.toml")
    server = ServerProcess(config, db_url, ict_dir, tmp_path / "server.log", workers).start()

    def call(kind: str, body: dict[str, Any]) -> dict[str, Any]:
        return post(server.url, f"/api/s/{token}/step", command(kind, body))

    try:
        token = post(server.url, "/api/sessions", {"participant_id": "K-3"})["token"]
        state = post(server.url, f"/api/s/{token}/step", {"command": "begin", "key": new_key()})
        state = run_to_end(state, call, stop=lambda s: s["stage"] == "trial"
                           and s["trial"]["task"] == "categorise")  # fmt: skip
        state = call("categorise", categorise_body(state))  # one answered
        server.kill()  # 1. between steps: the answer and the next face were committed
        server.start()
        assert httpx.get(f"{server.url}/api/s/{token}/state", timeout=30).json() == state
        body = categorise_body(state)  # 2. killed with an answer in flight: done once
        kill_with_step_in_flight(server, f"/api/s/{token}/step", {"command": "answer", **body})
        before = httpx.get(f"{server.url}/api/s/{token}/state", timeout=30).json()
        after = call("categorise", body)
        moved = before["progress"]["trial"] != state["progress"]["trial"]
        assert after.get("replayed", False) == moved
        assert after["progress"]["trial"] == state["progress"]["trial"] + 1
        assert run_to_end(after, call)["stage"] == "done"
    finally:
        server.stop()
    store = Store(db_url)
    tables = export_tables(store)
    responses = tables["categorise_responses"]
    assert len(responses) == 4 and responses["label"].notna().all()  # 2 own + 2 random, once
    assert not responses.duplicated(["trial"]).any()
    assert (tables["trials"]["status"] == "done").all()
    report = replay_session(store, 1, ict_model.rig, ict_model.model_hash, model=ict_model)
    assert report.ok and report.stimuli == 4, report.mismatches
    store.dispose()


def session_count(db_url: str, participant: str) -> int:
    from sqlalchemy import func, select

    from emogen.study.tables import SessionRow

    store = Store(db_url, migrate=False)
    try:
        with store.read() as db:
            query = select(func.count()).select_from(SessionRow)
            return int(db.scalar(query.where(SessionRow.participant_id == participant)) or 0)
    finally:
        store.dispose()


def test_a_create_whose_answer_is_lost_to_a_sigkill_gets_the_same_session_again(
    db_url: str, tmp_path: Path, ict_dir: Path
) -> None:
    """The consent page's create is committed, then the server is SIGKILLed before the page has
    read the answer: the page's retry (same participant id, same creation key) after the restart
    gets that session — not 409 "open your personal session link", a link it never saw."""
    import json
    import socket

    config = write_study_toml(SMALL_STUDY, tmp_path / "study.toml")
    server = ServerProcess(config, db_url, ict_dir, tmp_path / "server.log").start()
    body = {"participant_id": "LOST-1", "resume_token": None, "create_key": new_key() + "-ck"}
    raw = json.dumps(body).encode()
    try:
        with socket.create_connection(("127.0.0.1", server.port), timeout=30) as sock:
            sock.sendall(
                b"POST /api/sessions HTTP/1.1\r\nHost: 127.0.0.1\r\n"
                b"Content-Type: application/json\r\n"
                + f"Content-Length: {len(raw)}\r\n\r\n".encode()
                + raw
            )  # the answer is never read: lost, as behind a proxy that timed out
            for _ in range(600):  # until the create is committed (at most ~60 s)
                if session_count(db_url, "LOST-1") == 1:
                    break
                time.sleep(0.1)
            else:
                pytest.fail("the create was never committed")
            server.kill()
        server.start()
        r = httpx.post(f"{server.url}/api/sessions", json=body, timeout=30)
        assert r.status_code == 201, r.text
        token = r.json()["token"]
        again = httpx.post(f"{server.url}/api/sessions", json=body, timeout=30)
        assert again.status_code == 201 and again.json()["token"] == token
        # another browser (another key, or none) still needs the personal link
        for other in ({**body, "create_key": new_key() + "-xx"}, {"participant_id": "LOST-1"}):
            r = httpx.post(f"{server.url}/api/sessions", json=other, timeout=30)
            assert r.status_code == 409 and "personal session link" in r.json()["detail"]
    finally:
        server.stop()
    assert session_count(db_url, "LOST-1") == 1
