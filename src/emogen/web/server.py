"""Run the study server: ``emogen serve STUDY.toml --port 8000`` calls :func:`run_server`."""

from __future__ import annotations

import sys
from pathlib import Path


def run_server(
    config_path: Path,
    *,
    host: str = "127.0.0.1",
    port: int = 8000,
    database_url: str | None = None,
    model: Path | None = None,
    announce: bool = True,
    log_level: str = "warning",
    session_limit: str | None = None,
    hsts: bool = False,
) -> None:
    """Load the study, open (and migrate) the database, serve until interrupted.

    No access log: session links carry their secret token in the path. ``session_limit`` is a
    :meth:`RateLimit.parse` text (default 20/min per client address); ``hsts`` sends HSTS.
    """
    import uvicorn

    from emogen.study.config import load_study_config
    from emogen.web.app import create_app

    config = load_study_config(config_path)
    if model is not None:
        config = config.model_copy(update={"model": model})
    from emogen.errors import ConfigError
    from emogen.web.app import SESSION_LIMIT
    from emogen.web.ratelimit import RateLimit

    try:
        limit = SESSION_LIMIT if session_limit is None else RateLimit.parse(session_limit)
    except ValueError as exc:
        raise ConfigError(f"--session-limit: {exc}") from None
    app = create_app(config, database_url, session_limit=limit, hsts=hsts)
    if announce:
        shown = "localhost" if host in ("127.0.0.1", "0.0.0.0", "::") else host
        sys.stdout.write(
            f"EmoGen study '{config.name}' ({config.n_trials} trials), data in "
            f"{app.state.store.describe()}\n"
            f"  participants open:    http://{shown}:{port}/?{config.participant_param}=PARTICIPANT_ID\n"
            f"  researcher dashboard: http://{shown}:{port}/researcher"
            f"{'' if app.state.researcher_token else '  (set EMOGEN_RESEARCHER_TOKEN to enable)'}\n"
            "  stop with Ctrl-C\n"
        )
        sys.stdout.flush()
    uvicorn.run(
        app,
        host=host,
        port=port,
        log_level=log_level,
        access_log=False,
        timeout_graceful_shutdown=3,
    )
