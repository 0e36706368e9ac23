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


def _fail(message: str, code: int = 2) -> None:
    typer.secho(f"error: {message}", fg=typer.colors.RED, err=True)
    raise typer.Exit(code)


def friendly_errors(func: F) -> F:
    """Turn EmoGen's errors into one red line and exit status 2, with no traceback."""

    @wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return func(*args, **kwargs)
        except EmoGenError as exc:
            _fail(str(exc))

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
