# ruff: noqa: F811  (pytest fixtures imported by name, then requested by name)
"""The participant's way back in: resume links (CLI and researcher API), friendly pages for bad
session links, ``&render=png`` however it is appended, and the dashboard's numbering."""

from __future__ import annotations

from typing import Any

import pytest
from fastapi.testclient import TestClient
from typer.testing import CliRunner

from emogen.cli import app as cli
from tests.study.drive import choose, new_key, step_args
from tests.web.study_app import RESEARCHER_TOKEN, app, client, db_url, pg_cluster  # noqa: F401

AUTH = {"Authorization": f"Bearer {RESEARCHER_TOKEN}"}
pytestmark = pytest.mark.parametrize("db_url", ["sqlite"], indirect=True)


def start(client: TestClient, participant: str) -> str:
    r = client.post("/api/sessions", json={"participant_id": participant})
    assert r.status_code == 201, r.text
    return str(r.json()["token"])


def test_resume_link_from_the_cli(client: TestClient, db_url: str, monkeypatch) -> None:
    token = start(client, "P-cli@x")
    runner = CliRunner()
    monkeypatch.delenv("EMOGEN_BASE_URL", raising=False)
    args = ["study", "resume-link", "P-cli@x", "--database-url", db_url]
    result = runner.invoke(cli, [*args, "--base-url", "https://study.example.org/"])
    assert result.exit_code == 0, result.output
    assert result.output.strip() == f"https://study.example.org/s/{token}"
    result = runner.invoke(cli, args)  # the address `emogen serve` listens on by default
    assert result.output.strip() == f"http://127.0.0.1:8000/s/{token}"
    monkeypatch.setenv("EMOGEN_BASE_URL", "https://env.example.org")
    assert runner.invoke(cli, args).output.strip() == f"https://env.example.org/s/{token}"
    result = runner.invoke(cli, [*args, "--study", "small"])
    assert result.exit_code == 0 and token in result.output
    # no such participant (or study): exit 2, naming the id
    result = runner.invoke(cli, ["study", "resume-link", "P-none", "--database-url", db_url])
    assert result.exit_code == 2 and "participant 'P-none' has no session" in result.output
    result = runner.invoke(cli, [*args, "--study", "other"])
    assert result.exit_code == 2 and "in study 'other'" in result.output
    result = runner.invoke(cli, [*args, "--base-url", "study.example.org"])
    assert result.exit_code == 2 and "got 'study.example.org'" in result.output


def test_resume_link_from_the_researcher_api(client: TestClient) -> None:
    token = start(client, "P-api:1")
    url = "/api/researcher/participants/P-api:1/link"
    assert client.get(url).status_code == 403  # researchers only
    r = client.get(url, headers=AUTH)
    assert r.status_code == 200, r.text
    assert r.json() == {
        "participant_id": "P-api:1",
        "path": f"/s/{token}",
        "url": f"http://testserver/s/{token}",
    }
    assert client.get(url, headers=AUTH).json() == r.json()  # re-issued: the same link
    r = client.get("/api/researcher/participants/P-none/link", headers=AUTH)
    assert r.status_code == 404 and "participant 'P-none' has no session" in r.json()["detail"]
    r = client.get("/api/researcher/participants/has%20space/link", headers=AUTH)
    assert r.status_code == 422 and "got 'has space'" in r.json()["detail"]
    # the dashboard offers it per session, and its script asks this endpoint
    assert "session link" in client.get("/researcher").text
    assert "/api/researcher/participants/" in client.get("/static/researcher.js").text


def test_a_second_browser_is_told_where_its_link_is(client: TestClient) -> None:
    start(client, "P-twice")
    r = client.post("/api/sessions", json={"participant_id": "P-twice"})
    assert r.status_code == 409
    detail = r.json()["detail"]
    assert "'P-twice' already has a session" in detail
    assert "first page" in detail and "ask the researcher" in detail


@pytest.mark.parametrize(
    ("link", "status", "text"),
    [
        ("z" * 32, 404, "no session with this link"),  # well-formed, unknown (or gone)
        ("short", 404, "“short” is not a session link"),
        ("bad%20token%21", 404, "“bad token!” is not a session link"),
        ("x" * 200, 404, "“" + "x" * 37 + "...” is not a session link"),
    ],
)
def test_bad_session_links_get_a_friendly_page(
    client: TestClient, link: str, status: int, text: str
) -> None:
    r = client.get(f"/s/{link}")
    assert r.status_code == status
    assert r.headers["content-type"].startswith("text/html")
    assert "This session link is not valid" in r.text and text in r.text
    assert "ask the researcher for your personal session link" in r.text
    # the JSON API keeps JSON errors
    r = client.get(f"/api/s/{'z' * 32}/state")
    assert r.status_code == 404 and "no session" in r.json()["detail"]


def test_render_png_however_it_is_appended(client: TestClient) -> None:
    token = start(client, "P-png")
    for link, target in [
        (f"/s/{token}&render=png", f"/s/{token}?render=png"),
        (f"/s/{token}&render=png&x=1", f"/s/{token}?render=png&x=1"),
        (f"/s/{token}&render=png?x=1", f"/s/{token}?render=png&x=1"),
        (f"/s/{token}&", f"/s/{token}"),
    ]:
        r = client.get(link, follow_redirects=False)
        assert r.status_code == 307 and r.headers["location"] == target, (link, r.text)
        page = client.get(link)
        assert page.status_code == 200 and f'data-token="{token}"' in page.text
        assert str(page.url).endswith(target)
    assert client.get(f"/s/{token}?render=png").status_code == 200
    r = client.get(f"/s/{'z' * 32}&render=png")  # an unknown token stays a friendly 404
    assert r.status_code == 404 and "not valid" in r.text


def test_dashboard_numbers_generations_as_the_participant_saw_them(client: TestClient) -> None:
    token = start(client, "P-dash")

    def line() -> dict[str, Any]:
        sessions = client.get("/api/researcher/status", headers=AUTH).json()["sessions"]
        return next(s for s in sessions if s["participant_id"] == "P-dash")

    assert line()["step"] == "instructions"
    state = client.post(f"/api/s/{token}/step", json={"command": "begin", "key": new_key()}).json()
    # the page reads "Trial 1 of 2 · Round 1 of 3" (ga.generations = 2: generations 0 … 2)
    shown = line()
    assert (shown["trial"], shown["generation"]) == (1, 0)  # stored: generation from 0
    assert (shown["generation_shown"], shown["generations_shown"]) == (1, 3)
    assert shown["step"] == "trial 1 of 2 · generation 1 of 3"
    for g in range(3):
        elite, others = choose(state)
        body = {"key": new_key(), **step_args(state), "elite": elite, "others": others}
        state = client.post(f"/api/s/{token}/step", json={"command": "select", **body}).json()
        if g < 2:
            assert line()["step"] == f"trial 1 of 2 · generation {g + 2} of 3"
    assert state["trial"]["status"] == "rating"
    assert line()["step"] == "trial 1 of 2 · rating" and line()["generation_shown"] is None
    for t in range(2):
        if t:
            while state["trial"]["status"] == "active":
                elite, others = choose(state)
                body = {"key": new_key(), **step_args(state), "elite": elite, "others": others}
                state = client.post(
                    f"/api/s/{token}/step", json={"command": "select", **body}
                ).json()
        body = {"key": new_key(), "trial": t, "value": 5}
        state = client.post(f"/api/s/{token}/step", json={"command": "rate", **body}).json()
    assert state["stage"] == "done"
    assert (line()["step"], line()["trial"], line()["trials"]) == ("done", 2, 2)  # not 3 of 2
