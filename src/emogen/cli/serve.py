"""``emogen serve``: run a participant study (the web server)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from emogen.cli.options import friendly_errors
from emogen.cli.study import DatabaseOpt

__all__ = ["serve_command"]

HeaderTimeoutOpt = Annotated[
    float | None,
    typer.Option(
        "--header-timeout",
        help="Seconds a request's headers may take to arrive (408 beyond; default 15).",
    ),
]
BodyTimeoutOpt = Annotated[
    float | None,
    typer.Option(
        "--body-timeout",
        help="Seconds a request's body may take to arrive after its headers (408 and the "
        "connection closed beyond; default 20).",
    ),
]


@friendly_errors
def serve_command(
    config: Annotated[
        Path | None,
        typer.Argument(help="Study TOML (default: the packaged demo study)."),
    ] = None,
    host: Annotated[str, typer.Option("--host", help="Address to listen on.")] = "127.0.0.1",
    port: Annotated[int, typer.Option("--port", help="Port.")] = 8000,
    database_url: DatabaseOpt = None,
    model: Annotated[
        Path | None, typer.Option("--model", help="Face model (default: as in the config).")
    ] = None,
    session_limit: Annotated[
        str | None,
        typer.Option(
            "--session-limit",
            help="New sessions per client address: '30/min,burst=100' (default: a room of "
            "60 behind one address starts at once), '20/min', '5/min,burst=10' or 'off'.",
        ),
    ] = None,
    hsts: Annotated[
        bool,
        typer.Option("--hsts", help="Send Strict-Transport-Security (only behind HTTPS)."),
    ] = False,
    running_sessions: Annotated[
        str,
        typer.Option(
            "--running-sessions",
            help="When the config's design changed (not only its texts) while sessions begun "
            "under the earlier design are unfinished: 'refuse' to start (default) or 'end' them "
            "(their participants are told the study changed).",
        ),
    ] = "refuse",
    header_timeout: HeaderTimeoutOpt = None,
    body_timeout: BodyTimeoutOpt = None,
    workers: Annotated[
        int | None,
        typer.Option(
            "--workers",
            help="Worker processes (default: the number of cores). More than one on SQLite "
            "share one writer at a time; see docs/study.md for when to move to PostgreSQL.",
        ),
    ] = None,
) -> None:
    """Run a participant study: prints the URL to open; Ctrl-C stops it."""
    from emogen.cli.study_check import check_before_serving
    from emogen.errors import ConfigError, ResourceError
    from emogen.study.config import demo_study_path
    from emogen.web.app import viewer_built
    from emogen.web.server import run_server

    if running_sessions not in ("refuse", "end"):
        raise ConfigError(f"--running-sessions must be 'refuse' or 'end'; got {running_sessions!r}")
    path = config if config is not None else demo_study_path()
    check_before_serving(path)  # a bad config, then the study's errors, are named first
    if not viewer_built():
        raise ResourceError(
            "the face viewer bundle (emogen/web/static/build/study-viewer.js) is missing, so "
            "participants would see no faces: in a source checkout run `npm ci && npm run "
            "build` (or `make setup`); a wheel built with `pip wheel .` or `python -m build` "
            "carries it"
        )
    run_server(
        path,
        host=host,
        port=port,
        database_url=database_url,
        model=model,
        session_limit=session_limit,
        hsts=hsts,
        workers=workers,
        running_sessions=running_sessions,
        header_timeout=header_timeout,
        body_timeout=body_timeout,
    )
