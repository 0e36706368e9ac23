"""A computer room behind one address (a university NAT): with the server's default limits 60
participants starting within a minute all get a session, while an address that keeps making
sessions is still refused (429 with Retry-After) and other addresses are not affected."""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any

from fastapi.testclient import TestClient

from emogen.study.config import study_from_dict
from emogen.web.app import SESSION_LIMIT
from emogen.web.ratelimit import TokenBuckets
from tests.study.conftest import SMALL_STUDY

ROOM = 60


def test_a_room_of_60_behind_one_address_starts_and_a_flood_is_still_refused(
    tmp_path: Path, ict_model: Any
) -> None:
    from emogen.web import create_app

    # the defaults: no session_limit given, as `emogen serve` without --session-limit
    app = create_app(
        study_from_dict(SMALL_STUDY),
        f"sqlite:///{tmp_path / 'room.sqlite'}",
        model=ict_model,
        researcher_token="lab-room-researcher-token-0123456789",
    )
    nat = ("192.0.2.10", 50000)
    with TestClient(app, client=nat) as room, TestClient(app, client=("192.0.2.99", 1)) as home:
        start = time.monotonic()
        answers = [
            room.post("/api/sessions", json={"participant_id": f"LAB-{i}"}) for i in range(ROOM)
        ]
        assert time.monotonic() - start < 60
        assert [a.status_code for a in answers] == [201] * ROOM
        assert len({a.json()["token"] for a in answers}) == ROOM
        # the same address keeps going, as a script would: refused once the burst is spent
        made = ROOM
        while (r := room.post("/api/sessions", json={})).status_code == 201:
            made += 1
            assert made <= 2 * ROOM + 40, "no limit on one address"
        elapsed = time.monotonic() - start
        assert r.status_code == 429 and "too many new sessions" in r.json()["detail"]
        refilled = SESSION_LIMIT.per_minute * elapsed / 60
        assert SESSION_LIMIT.burst <= made <= SESSION_LIMIT.burst + math.ceil(refilled)
        assert 1 <= int(r.headers["retry-after"]) <= math.ceil(60 / SESSION_LIMIT.per_minute)
        assert home.post("/api/sessions", json={"participant_id": "HOME-1"}).status_code == 201


def test_the_default_limit_holds_a_flood_to_a_bounded_rate() -> None:
    now = [0.0]
    buckets = TokenBuckets(SESSION_LIMIT, clock=lambda: now[0])
    # a room of 60 at once, then another 60 two minutes later: all in, without waiting
    assert [buckets.take("nat") for _ in range(ROOM)] == [0.0] * ROOM
    now[0] = 120.0
    assert [buckets.take("nat") for _ in range(ROOM)] == [0.0] * ROOM
    # a script trying ten times a second for an hour: 100 at once, then 30 a minute
    made = 0
    for step in range(36_000):
        now[0] = 1000.0 + step / 10
        made += buckets.take("script") == 0
    assert 100 + 30 * 60 - 1 <= made <= 100 + 30 * 60  # the last token may be mid-refill
