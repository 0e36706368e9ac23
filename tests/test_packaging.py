"""The wheel carries the face viewer bundle (hatch_build.py), and `emogen serve` without it says
what is missing instead of serving a study that shows no faces."""

from __future__ import annotations

import importlib.util
import stat
import sys
import types
from pathlib import Path

import pytest
from typer.testing import CliRunner

from emogen.cli import app

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture
def hook(monkeypatch: pytest.MonkeyPatch) -> types.ModuleType:
    """hatch_build.py, imported without hatchling (only the build's own environment has it)."""
    names = [
        "hatchling",
        "hatchling.builders",
        "hatchling.builders.hooks",
        "hatchling.builders.hooks.plugin",
        "hatchling.builders.hooks.plugin.interface",
    ]
    for name in names:
        monkeypatch.setitem(sys.modules, name, types.ModuleType(name))
    sys.modules[names[-1]].BuildHookInterface = object  # type: ignore[attr-defined]
    spec = importlib.util.spec_from_file_location("hatch_build", REPO / "hatch_build.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_wheel_hook_is_configured() -> None:
    text = (REPO / "pyproject.toml").read_text()
    assert "[tool.hatch.build.targets.wheel.hooks.custom]" in text
    assert 'artifacts = ["src/emogen/web/static/build/**"]' in text


def test_a_clean_checkout_builds_the_bundle_with_npm(hook, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    (tmp_path / "package.json").write_text("{}")
    log = tmp_path / "npm.log"
    npm = tmp_path / "npm"
    npm.write_text(
        "#!/bin/sh\n"
        f'echo "$@" >> {log}\n'
        'if [ "$1" = ci ]; then mkdir -p node_modules; fi\n'
        'if [ "$1 $2" = "run build" ]; then mkdir -p src/emogen/web/static/build && '
        "echo bundle > src/emogen/web/static/build/study-viewer.js; fi\n"
    )
    npm.chmod(npm.stat().st_mode | stat.S_IEXEC)
    bundle = hook.ensure_viewer(tmp_path, npm=str(npm))
    assert bundle.read_text() == "bundle\n"
    assert log.read_text().splitlines() == ["ci --no-audit --no-fund", "run build"]
    assert hook.ensure_viewer(tmp_path, npm=str(npm)) == bundle  # built: nothing runs again
    assert len(log.read_text().splitlines()) == 2


def test_without_npm_the_build_stops_saying_what_to_install(hook, tmp_path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.setattr(hook.shutil, "which", lambda _name: None)
    with pytest.raises(RuntimeError, match=r"study-viewer\.js is missing .*npm is not installed"):
        hook.ensure_viewer(tmp_path)


def test_serve_without_the_viewer_bundle_says_what_is_missing(monkeypatch) -> None:  # type: ignore[no-untyped-def]
    import emogen.web.app

    monkeypatch.setattr(emogen.web.app, "viewer_built", lambda: False)
    result = CliRunner().invoke(app, ["serve", "--port", "1"])
    assert result.exit_code == 4
    assert "viewer bundle" in result.output and "npm run build" in result.output
