"""Attacks on a real ``emogen serve`` on 127.0.0.1 (issue 33), bounded in time and count.

An oversized request head is answered 431 and costs the server one socket read beyond the
limit; half-sent heads are answered 408 once the header timeout has passed (the attack holds
nothing longer); wrong researcher tokens are limited by one count shared by every worker
process, so a brute force gets the burst and no more, and the right token waits too; a short
researcher token is refused at start, naming the problem.
"""

from __future__ import annotations

import contextlib
import socket
import time
from pathlib import Path

import httpx
import pytest
from benchmarks.bench_study import BENCH_TOKEN, ServerProcess, free_port, write_study_toml
from typer.testing import CliRunner

from emogen.errors import ConfigError
from tests.study.conftest import SMALL_STUDY

pytestmark = pytest.mark.slow
HEAD_TIMEOUT_S = 2


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory, ict_dir: Path):  # type: ignore[no-untyped-def]
    folder = tmp_path_factory.mktemp("attacks")
    config = write_study_toml(SMALL_STUDY, folder / "study.toml")
    proc = ServerProcess(
        config,
        f"sqlite:///{folder / 'study.sqlite'}",
        ict_dir,
        folder / "server.log",
        workers=2,
        extra=("--header-timeout", str(HEAD_TIMEOUT_S)),
    ).start()
    yield proc
    proc.stop()


def answer_of(sock: socket.socket) -> bytes:
    """What the server answers before it closes (b"" if it closes without a word)."""
    got = b""
    with contextlib.suppress(ConnectionResetError):
        while chunk := sock.recv(65536):
            got += chunk
    return got


def test_an_oversized_header_is_431_and_the_server_goes_on(server: ServerProcess) -> None:
    with socket.create_connection(("127.0.0.1", server.port), timeout=20) as sock:
        head = b"GET /healthz HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Big: " + b"a" * (4 << 20)
        with contextlib.suppress(BrokenPipeError, ConnectionResetError):
            sock.sendall(head)  # the server stops reading long before the end
        assert answer_of(sock).startswith(b"HTTP/1.1 431 ")
    assert httpx.get(f"{server.url}/healthz", timeout=10).status_code == 200
    r = httpx.get(f"{server.url}/healthz", headers={"X-Ok": "b" * 8000}, timeout=10)
    assert r.status_code == 200  # an ordinary large header passes


def test_half_sent_requests_are_408_after_the_header_timeout(server: ServerProcess) -> None:
    socks = [socket.create_connection(("127.0.0.1", server.port), timeout=20) for _ in range(40)]
    try:
        for i, sock in enumerate(socks):
            if i % 4:  # three in four send part of a head; the others nothing at all
                sock.sendall(b"POST /api/sessions HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: ")
        start = time.monotonic()
        trickle = socks[1]
        while time.monotonic() - start < HEAD_TIMEOUT_S + 1:  # a slowloris keeps sending
            with contextlib.suppress(OSError):
                trickle.sendall(b"x")
            assert httpx.get(f"{server.url}/healthz", timeout=10).status_code == 200
            time.sleep(0.25)
        answers = [answer_of(sock) for sock in socks]
    finally:
        for sock in socks:
            sock.close()
    assert all(a.startswith(b"HTTP/1.1 408 ") for a in answers), {a[:20] for a in answers}


def test_wrong_researcher_tokens_are_counted_across_workers(server: ServerProcess) -> None:
    deadline = time.monotonic() + 30  # both workers idle in their event loop (not mid-request)
    while server.ready_workers() < 2 and time.monotonic() < deadline:
        time.sleep(0.2)
    assert server.ready_workers() == 2
    statuses = []
    for i in range(30):  # a brute force, a new connection each (any worker may take it)
        r = httpx.get(
            f"{server.url}/api/researcher/status",
            timeout=10,
            headers={"Authorization": f"Bearer guess-{i:04d}-{'x' * 40}"},
        )
        statuses.append(r.status_code)
    assert statuses.count(403) == 10 and statuses.count(429) == 20, statuses
    right = [
        httpx.get(
            f"{server.url}/api/researcher/status",
            timeout=10,
            headers={"Authorization": f"Bearer {BENCH_TOKEN}"},
        ).status_code
        for _ in range(20)
    ]
    assert right == [429] * 20  # while the address waits, even the right token waits


def test_a_short_researcher_token_is_refused_at_start(tmp_path: Path, ict_model) -> None:  # type: ignore[no-untyped-def]
    from emogen.cli.app import app as cli
    from emogen.study.config import study_from_dict
    from emogen.web import create_app

    for weak, problem in (
        ("secret", "6 characters long; it must be at least 32"),
        ("ab" * 20, "only 2 different characters"),
    ):
        with pytest.raises(ConfigError, match=problem):
            create_app(
                study_from_dict(SMALL_STUDY),
                f"sqlite:///{tmp_path / 'a.sqlite'}",
                model=ict_model,
                researcher_token=weak,
            )
    config = write_study_toml(SMALL_STUDY, tmp_path / "study.toml")
    result = CliRunner().invoke(
        cli,
        [
            "serve",
            str(config),
            "--port",
            str(free_port()),
            "--database-url",
            f"sqlite:///{tmp_path / 'b.sqlite'}",
        ],
        env={"EMOGEN_RESEARCHER_TOKEN": "hunter2"},
    )
    assert result.exit_code != 0
    assert "EMOGEN_RESEARCHER_TOKEN is 7 characters long" in result.output
