"""`emogen serve` says what it is doing while it loads (the first start after an install
compiles the face correction: a silent pause of ~20 s otherwise), checks its address before
anything loads, and prints the banner with the links once the address accepts connections."""

from __future__ import annotations

import socket
import time
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

from emogen.errors import ConfigError, ResourceError
from emogen.study.config import study_from_dict
from tests.study.conftest import SMALL_STUDY


def fake_app() -> Any:
    config = study_from_dict(SMALL_STUDY)
    store = SimpleNamespace(describe=lambda: "sqlite:///x.sqlite", dispose=lambda: None)
    service = SimpleNamespace(n_trials=config.n_trials)  # the banner says how many trials
    made: list[float] = []  # when every identity's GLB was made (before listening)
    glbs = SimpleNamespace(made=made, make_all=lambda: made.append(time.monotonic()))
    return SimpleNamespace(
        state=SimpleNamespace(
            config=config, store=store, service=service, researcher_token=None, glbs=glbs
        )
    )


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def run(monkeypatch: pytest.MonkeyPatch, make: Any, serve: Any, port: int) -> None:
    """run_server with the study and app faked and uvicorn.run replaced by ``serve``."""
    import uvicorn

    import emogen.study.config as config
    from emogen.web import app as web_app
    from emogen.web import server

    monkeypatch.setattr(config, "load_study_config", lambda path: study_from_dict(SMALL_STUDY))
    monkeypatch.setattr(uvicorn, "run", serve)
    monkeypatch.setattr(web_app, "create_app", make)
    server.run_server(Path("x.toml"), session_limit="off", workers=1, port=port)


def listening_server(capsys: pytest.CaptureFixture[str], before: list[str]) -> Any:
    """A stand-in for uvicorn.run: a moment before listening (what was printed by then is
    kept in ``before``), then listening on the port for a while."""

    def serve(app: Any, **kw: Any) -> None:
        time.sleep(0.4)
        before.append(capsys.readouterr().out)
        with socket.socket() as s:
            s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            s.bind((kw["host"], kw["port"]))
            s.listen()
            time.sleep(1.0)

    return serve


def test_the_loading_line_then_the_banner_once_the_address_accepts_connections(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    printed_before: list[str] = []

    apps: list[Any] = []

    def make(*args: Any, **kwargs: Any) -> Any:
        printed_before.append(capsys.readouterr().out)
        apps.append(fake_app())
        return apps[-1]

    before_listening: list[str] = []
    run(monkeypatch, make, listening_server(capsys, before_listening), free_port())
    # every identity's 3D model made while loading, not at a participant's first request
    assert len(apps[0].state.glbs.made) == 1
    after = capsys.readouterr().out
    assert printed_before[0].startswith("Loading the study and the face model")
    assert "compile the face correction" in printed_before[0]
    # loaded: 'ready', but no links while nothing listens
    assert before_listening[0].startswith("ready (") and before_listening[0].endswith(" s)\n")
    assert "participants open" not in before_listening[0]
    assert after.startswith("EmoGen study 'small' (2 trials)")
    assert "participants open:    http://localhost:" in after
    # the session length from the design: 2 trials × 3 generations shown; 102–184 s
    assert "a session takes about 2–4 minutes (6 selection screens × 6–9 s" in after


def test_no_banner_when_the_server_never_listens(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    run(monkeypatch, lambda *a, **kw: fake_app(), lambda app, **kw: None, free_port())
    time.sleep(0.3)  # the banner's thread has stopped waiting
    out = capsys.readouterr().out
    assert out.startswith("Loading the study") and "participants open" not in out


def test_a_port_in_use_is_refused_before_anything_loads(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    made: list[int] = []
    served: list[int] = []
    with socket.socket() as other:
        other.bind(("127.0.0.1", 0))
        other.listen()
        port = other.getsockname()[1]
        with pytest.raises(ResourceError, match=f"port {port} is in use.*--port"):
            run(
                monkeypatch, lambda *a, **kw: made.append(1), lambda a, **kw: served.append(1), port
            )
    assert made == [] and served == [] and capsys.readouterr().out == ""


@pytest.mark.parametrize(
    ("host", "port", "error", "match"),
    [
        ("127.0.0.1", 70000, ConfigError, "--port must be in 1..65535; got 70000"),
        ("127.0.0.1", 0, ConfigError, "--port must be in 1..65535; got 0"),
        ("no-such-host.invalid", 8000, ResourceError, "cannot listen on no-such-host.invalid"),
    ],
)
def test_a_bad_address_is_named(host: str, port: int, error: type, match: str) -> None:
    from emogen.web.server import check_address

    with pytest.raises(error, match=match):
        check_address(host, port)


def test_a_failing_load_ends_the_line_before_the_error(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    def make(*args: Any, **kwargs: Any) -> Any:
        raise ConfigError("model folder 'nowhere' does not exist")

    with pytest.raises(ConfigError, match="nowhere"):
        run(monkeypatch, make, lambda app, **kw: None, free_port())
    out = capsys.readouterr().out
    assert out.startswith("Loading the study") and out.endswith(" ... \n")
