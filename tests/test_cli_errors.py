"""The command line's one error path: one line on stderr, the exit status of its kind (2 usage,
3 data, 4 environment; docs/cli.md), nothing written; and output folders written all or nothing."""

from __future__ import annotations

import errno
import os
import re
import subprocess
import sys
from pathlib import Path

import click
import pytest
import typer
from typer.testing import CliRunner

from emogen.cli import app
from emogen.cli.options import EXIT_DATA, EXIT_ENVIRONMENT, EXIT_USAGE, friendly_errors
from emogen.cli.outputs import output_folder
from emogen.errors import ConfigError, DataError, ModelFileError, ResourceError
from emogen.render.errors import RenderError

runner = CliRunner()


def _commands(group: click.Command, prefix: str = "") -> list[tuple[str, click.Command]]:
    out = [(prefix.strip(), group)]
    if isinstance(group, click.Group):
        for name, cmd in group.commands.items():
            out.extend(_commands(cmd, f"{prefix} {name}"))
    return out


def test_every_command_goes_through_the_one_error_path() -> None:
    missing = [
        name
        for name, cmd in _commands(typer.main.get_command(app))
        if cmd.callback is not None
        and name  # the app's own callback only handles --version
        and not getattr(cmd.callback, "__emogen_errors__", False)
        and not (isinstance(cmd, click.Group) and name != "render")
    ]
    assert missing == []


@pytest.mark.parametrize(
    ("exc", "status"),
    [
        (ConfigError("bad --x"), EXIT_USAGE),
        (DataError("table row 1"), EXIT_DATA),
        (ModelFileError("cut"), EXIT_DATA),
        (ResourceError("db down"), EXIT_ENVIRONMENT),
        (RenderError("no OpenGL context could be made"), EXIT_ENVIRONMENT),
        (
            OSError(errno.ENOSPC, "No space left on device", "/full/disk/x.parquet"),
            EXIT_ENVIRONMENT,
        ),
        (PermissionError(errno.EACCES, "Permission denied", "/ro/out"), EXIT_ENVIRONMENT),
        (OSError(errno.EROFS, "Read-only file system", "/ro/out"), EXIT_ENVIRONMENT),
        (FileExistsError(errno.EEXIST, "File exists", "/x/out"), EXIT_USAGE),
    ],
)
def test_each_kind_of_error_has_its_status_and_one_line(exc: Exception, status: int) -> None:
    demo = typer.Typer()

    @demo.command()
    @friendly_errors
    def fail() -> None:
        raise exc

    result = runner.invoke(demo, [])
    assert result.exit_code == status
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and "Traceback" not in result.output
    if isinstance(exc, OSError):
        assert str(exc.filename) in lines[0] and exc.strerror in lines[0]


def test_no_colour_with_no_color_set(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    # a real terminal is not available here: the rule is checked directly, and the process
    # output (not a terminal) carries no escape codes either way
    from emogen.cli import options

    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    monkeypatch.setenv("NO_COLOR", "1")
    assert not options.use_colour()
    monkeypatch.delenv("NO_COLOR")
    assert options.use_colour()
    proc = subprocess.run(
        [sys.executable, "-m", "emogen", "study", "status", "--database-url", str(tmp_path / "n")],
        capture_output=True,
        text=True,
        env={**os.environ, "NO_COLOR": "1"},
    )
    assert proc.returncode == EXIT_ENVIRONMENT and "\x1b[" not in proc.stderr


# ---- read-only study commands never create a database ------------------------------------
@pytest.mark.parametrize(
    "args",
    [
        ["study", "status"],
        ["study", "export", "--out", "OUT"],
        ["study", "resume-link", "P1"],
        ["replay", "1"],
    ],
)
def test_a_mistyped_sqlite_path_is_an_error_and_creates_nothing(
    tmp_path: Path, args: list[str]
) -> None:
    db = tmp_path / "typo" / "sub" / "study.sqlite"
    argv = [a.replace("OUT", str(tmp_path / "out")) for a in args]
    result = runner.invoke(app, [*argv, "--database-url", f"sqlite:///{db}"])
    assert result.exit_code == EXIT_ENVIRONMENT, result.output
    assert str(db) in result.output and "does not exist" in result.output
    assert list(tmp_path.iterdir()) == []  # no database, no folders, no export


def test_an_empty_file_is_not_a_database(tmp_path: Path) -> None:
    empty = tmp_path / "study.sqlite"
    empty.touch()
    result = runner.invoke(app, ["study", "status", "--database-url", str(empty)])
    assert result.exit_code == EXIT_ENVIRONMENT and "empty file" in result.output
    assert empty.stat().st_size == 0


def test_an_unreachable_postgresql_server_is_one_line_without_the_password() -> None:
    url = "postgresql://alice:s3cret@127.0.0.1:9/studies"  # port 9 (discard): refused
    result = runner.invoke(app, ["study", "status", "--database-url", url])
    assert result.exit_code == EXIT_ENVIRONMENT, result.output
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and "s3cret" not in result.output
    assert "alice:***@127.0.0.1:9/studies" in lines[0] and "server running" in lines[0]


# ---- output folders ---------------------------------------------------------------------
def test_output_folder_refuses_a_non_empty_folder_and_a_file(tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    (out / "simulation.json").write_text("{}")
    message = r"not empty \(1 entries, e.g. 'simulation.json'\)"
    with pytest.raises(ConfigError, match=message), output_folder(out, force=False):
        pass
    afile = tmp_path / "a.txt"
    afile.write_text("x")
    with pytest.raises(ConfigError, match="is a file"), output_folder(afile, force=True):
        pass
    assert afile.read_text() == "x"


def test_a_failed_run_leaves_the_old_output_untouched(tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    (out / "seed2.json").write_text("old")
    with pytest.raises(RuntimeError), output_folder(out, force=True) as tmp:
        (tmp / "seed3.parquet").write_text("new, half written")
        raise RuntimeError("disk full halfway")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]  # no partial folder left
    assert [p.name for p in out.iterdir()] == ["seed2.json"]


def test_force_replaces_the_folder_only_when_complete(tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    (out / "seed2.json").write_text("old")
    with output_folder(out, force=True) as tmp:
        assert tmp != out and tmp.parent == out.parent
        assert (out / "seed2.json").exists()  # still there while writing
        (tmp / "seed3.json").write_text("new")
    assert [p.name for p in out.iterdir()] == ["seed3.json"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]
    assert out.stat().st_mode & 0o777 == 0o777 & ~_umask()


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def test_study_export_into_a_non_empty_folder_is_refused(tmp_path: Path) -> None:
    out = tmp_path / "export"
    out.mkdir()
    (out / "keep.txt").write_text("mine")
    db = tmp_path / "none.sqlite"
    result = runner.invoke(app, ["study", "export", "--out", str(out), "--database-url", str(db)])
    assert result.exit_code == EXIT_USAGE and "--force" in result.output
    assert [p.name for p in out.iterdir()] == ["keep.txt"] and not db.exists()


# ---- option values ----------------------------------------------------------------------
@pytest.mark.parametrize(
    ("args", "option"),
    [
        (["render", "--size", "0", "--out", "a.png"], "--size"),
        (["render", "sheet", "--size", "0", "--out", "a.png"], "--size"),
        (["render", "sheet", "--columns", "0", "--out", "a.png"], "--columns"),
        (["render", "--supersample", "0", "--out", "a.png"], "--supersample"),
        (["simulate", "--workers", "0", "--out", "o", "-t", "jawOpen=1"], "--workers"),
        (["simulate", "--runs", "0", "--out", "o", "-t", "jawOpen=1"], "--runs"),
        (["simulate", "--generations", "0", "--out", "o", "-t", "jawOpen=1"], "--generations"),
        (["sweep", "s.toml", "--workers", "0", "--out", "o"], "--workers"),
        (["analyse", "d", "--noise-runs", "0", "--out", "o"], "--noise-runs"),
    ],
)
def test_zero_sizes_and_counts_are_usage_errors_naming_the_value(
    args: list[str], option: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    result = runner.invoke(app, args)
    assert result.exit_code == EXIT_USAGE, result.output
    text = " ".join(re.sub("[│╭╮╰╯─]", " ", result.output).split())
    assert f"Invalid value for '{option}': must be at least 1; got 0" in text
    assert list(tmp_path.iterdir()) == []


def test_serve_with_an_unreachable_postgresql_server_is_one_line(ict_dir: Path) -> None:
    url = "postgresql://alice:s3cret@127.0.0.1:9/studies"
    args = ["serve", "--database-url", url, "--port", "1", "--model", str(ict_dir)]
    result = runner.invoke(app, args)
    assert result.exit_code == EXIT_ENVIRONMENT, result.output
    assert len(result.output.strip().splitlines()) == 1 and "s3cret" not in result.output
    assert "cannot open the study database" in result.output


def test_a_reader_that_goes_away_is_not_an_error(ict_dir: Path) -> None:
    """``emogen model info | head -n 4``: when stdout's reader has gone, the command stops
    quietly (status 141, as Unix tools do), not with an 'error: … Broken pipe' line."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "emogen", "model", "info", "--model", str(ict_dir)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    assert proc.stdout is not None and proc.stderr is not None
    proc.stdout.close()  # the reader goes before the command writes (it loads the model first)
    err = proc.stderr.read().decode()
    assert proc.wait(120) == 141
    assert err == "", err


def test_broken_pipe_inside_a_command_exits_141_without_a_line(
    capsys: pytest.CaptureFixture[str],
) -> None:
    @friendly_errors
    def writes() -> None:
        raise BrokenPipeError(errno.EPIPE, "Broken pipe")

    with pytest.raises(SystemExit) as stop:
        writes()
    assert stop.value.code == 141
    assert capsys.readouterr().err == ""
