"""Helpers shared by every `emogen` command module: option types, error handling, parsing.

A leaf module (it imports no command module), so the command groups defined beside their
packages (render, correct, study, analysis) and ``emogen.cli`` can all import it.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import wraps
from pathlib import Path
from typing import Annotated, Any, TypeVar

import typer

from emogen.errors import EmoGenError

F = TypeVar("F", bound=Callable[..., Any])

ModelOpt = Annotated[
    Path | None,
    typer.Option(
        "--model",
        help="ICT-FaceKit FaceXModel folder or GLB (default: $EMOGEN_MODEL, then the user cache).",
    ),
]
FigureFormatOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--format",
        help="Figure formats: png (300 dpi), svg, pdf; repeatable or comma-separated "
        "(default png,svg; png is always written, the report shows it).",
    ),
]
RigOpt = Annotated[
    Path | None, typer.Option("--rig", help="Rig TOML (default: the packaged ICT rig).")
]


def at_least(minimum: int) -> Callable[[int | None], int | None]:
    """An option callback: the value must be at least ``minimum`` (a usage error naming it)."""

    def check(value: int | None) -> int | None:
        if value is not None and value < minimum:
            raise typer.BadParameter(f"must be at least {minimum}; got {value}")
        return value

    return check


def _shape_of(name: str | None) -> str | None:
    """An identity preset's shape (``female-dark`` → ``female``); other names unchanged."""
    if name is None:
        return None
    from emogen.appearance.identities import PRESETS

    preset = PRESETS.get(name)
    return preset.shape if preset is not None and isinstance(preset.shape, str) else name


#: The face shape of commands that use no appearance (model export, correct).
IdentityOpt = Annotated[
    str | None,
    typer.Option(
        "--identity",
        help="Shape preset (generic, male, female); an identity preset (e.g. female-dark) "
        "gives its shape.",
        callback=_shape_of,
    ),
]


#: Exit statuses of every command (docs/cli.md). 1 is a check that found a difference (replay).
EXIT_USAGE, EXIT_DATA, EXIT_ENVIRONMENT = 2, 3, 4
#: stdout's reader went away (a pipe into `head`): stopped quietly, as Unix tools do
EXIT_BROKEN_PIPE = 141


def use_colour() -> bool:
    """Colour on stderr only on a terminal, and never with ``NO_COLOR`` set (no-color.org)."""
    import os
    import sys

    return not os.environ.get("NO_COLOR") and sys.stderr.isatty()


def _fail(message: str, code: int = EXIT_USAGE) -> None:
    typer.secho(
        f"error: {message}", fg=typer.colors.RED if use_colour() else None, err=True, color=None
    )
    raise typer.Exit(code)


def exit_status(exc: BaseException) -> int:
    """The exit status of an error: 2 usage, 3 data, 4 environment (see docs/cli.md)."""
    from emogen.errors import DataError, ModelFileError, ModelNotFoundError, ResourceError
    from emogen.render.errors import RenderError  # no OpenGL context, an image not written

    if isinstance(exc, ResourceError | ModelNotFoundError | RenderError):
        return EXIT_ENVIRONMENT
    if isinstance(exc, DataError | ModelFileError):
        return EXIT_DATA
    return EXIT_USAGE


def os_error_message(exc: OSError) -> tuple[str, int]:
    """One line for an operating-system error, naming the file and what to do, and its status."""
    import errno

    where = " ".join(str(f) for f in (exc.filename, exc.filename2) if f is not None)
    what = exc.strerror or str(exc)
    if isinstance(exc, FileExistsError | IsADirectoryError | NotADirectoryError):
        return f"{where}: {what} (give a new path, or the kind of path the option asks for)", (
            EXIT_USAGE
        )
    hints = {
        errno.ENOSPC: "the disk is full: free some space or write somewhere else",
        errno.EDQUOT: "the disk quota is used up: free some space or write somewhere else",
        errno.EROFS: "the file system is read-only: write somewhere else",
        errno.EACCES: "permission denied: write somewhere you may write, or fix the permissions",
        errno.EPERM: "not permitted: write somewhere you may write, or fix the permissions",
    }
    hint = hints.get(exc.errno or 0, "check the path and try again")
    return f"{where or 'a file'}: {what} ({hint})", EXIT_ENVIRONMENT


def _reader_gone() -> None:
    """The reader of stdout went away (``emogen model info | head -n 4``): not an error of
    ours. Stop quietly, as Unix tools do (status 141 = 128 + SIGPIPE), with stdout pointed at
    /dev/null so that flushing it at exit raises nothing more."""
    import os
    import sys

    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):  # not a real file (captured, closed)
        fd = None
    if fd is not None:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, fd)
        os.close(devnull)
    raise SystemExit(EXIT_BROKEN_PIPE)


def friendly_errors(func: F) -> F:
    """The one error path of every command: EmoGen's errors and the operating system's become
    one red line on stderr (no traceback) and the exit status of their kind (2 usage, 3 data,
    4 environment; see :func:`exit_status`)."""

    @wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return func(*args, **kwargs)
        except EmoGenError as exc:
            _fail(str(exc), exit_status(exc))
        except BrokenPipeError:
            _reader_gone()
        except OSError as exc:
            message, code = os_error_message(exc)
            _fail(message, code)

    wrapper.__emogen_errors__ = True  # type: ignore[attr-defined]
    return wrapper  # type: ignore[return-value]


def parse_named_weights(items: list[str] | None, option: str = "--weight") -> dict[str, float]:
    """``["jawOpen=0.8", ...]`` → ``{"jawOpen": 0.8}`` with errors that name the bad item."""
    from emogen.errors import ConfigError

    out: dict[str, float] = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise ConfigError(f"{option} must look like NAME=VALUE; got {item!r}")
        try:
            out[name.strip()] = float(value)
        except ValueError:
            raise ConfigError(f"{option} {item!r}: value {value!r} is not a number") from None
    return out


SeedOpt = Annotated[int, typer.Option("--seed", help="Seed of every simulation (recorded).")]
JsonOpt = Annotated[
    bool,
    typer.Option("--json", help="Print the result as one JSON object on stdout (nothing else)."),
]


def stage_printer(enabled: bool | None = None) -> Callable[[str], None] | None:
    """Progress of a long command, one line per stage with the elapsed time, on stderr — only
    when stderr is a terminal (``enabled=None``), so pipes, logs and ``--json`` stay clean."""
    import sys
    import time

    if enabled is None:
        enabled = sys.stderr.isatty()
    if not enabled:
        return None
    start = time.perf_counter()

    def show(stage: str) -> None:
        typer.secho(
            f"[{time.perf_counter() - start:6.1f} s] {stage}",
            err=True,
            dim=use_colour(),
        )

    return show


def show_result(as_json: bool, data: dict[str, Any], lines: list[str]) -> None:
    """A command's result: one JSON object on stdout with ``--json``, else the text lines."""
    if as_json:
        import json

        typer.echo(json.dumps(data, indent=2, default=str))
        return
    for line in lines:
        typer.echo(line)
