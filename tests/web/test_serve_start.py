"""`emogen serve` says what it is doing while it loads (the first start after an install
compiles the face correction: a silent pause of ~20 s otherwise), then prints the banner."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

from emogen.errors import ConfigError
from emogen.study.config import study_from_dict
from tests.study.conftest import SMALL_STUDY


def fake_app() -> Any:
    config = study_from_dict(SMALL_STUDY)
    store = SimpleNamespace(describe=lambda: "sqlite:///x.sqlite", dispose=lambda: None)
    return SimpleNamespace(state=SimpleNamespace(config=config, store=store, researcher_token=None))


def run(monkeypatch: pytest.MonkeyPatch, make: Any) -> None:
    import uvicorn

    import emogen.study.config as config
    from emogen.web import app as web_app
    from emogen.web import server

    monkeypatch.setattr(config, "load_study_config", lambda path: study_from_dict(SMALL_STUDY))
    monkeypatch.setattr(uvicorn, "run", lambda app, **kw: None)
    monkeypatch.setattr(web_app, "create_app", make)
    server.run_server(Path("x.toml"), session_limit="off", workers=1)


def test_the_loading_line_comes_before_the_app_is_made_then_the_banner(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    printed_before: list[str] = []

    def make(*args: Any, **kwargs: Any) -> Any:
        printed_before.append(capsys.readouterr().out)
        return fake_app()

    run(monkeypatch, make)
    after = capsys.readouterr().out
    assert printed_before[0].startswith("Loading the study and the face model")
    assert "compile the face correction" in printed_before[0]
    first, banner = after.split("\n", 1)
    assert first.startswith("ready (") and first.endswith(" s)")
    assert banner.startswith("EmoGen study 'small' (2 trials)")


def test_a_failing_load_ends_the_line_before_the_error(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    def make(*args: Any, **kwargs: Any) -> Any:
        raise ConfigError("model folder 'nowhere' does not exist")

    with pytest.raises(ConfigError, match="nowhere"):
        run(monkeypatch, make)
    out = capsys.readouterr().out
    assert out.startswith("Loading the study") and out.endswith(" ... \n")
