"""Run the study server: ``python -m emogen.web.server STUDY.toml --port 8000``.

``emogen serve`` calls :func:`run_server`; tests and the benchmark start this module in a
subprocess.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from emogen.errors import EmoGenError


def run_server(
    config_path: Path,
    *,
    host: str = "127.0.0.1",
    port: int = 8000,
    database_url: str | None = None,
    model: Path | None = None,
    announce: bool = True,
    log_level: str = "warning",
) -> None:
    """Load the study, open (and migrate) the database, serve until interrupted."""
    import uvicorn

    from emogen.study.config import load_study_config
    from emogen.web.app import create_app

    config = load_study_config(config_path)
    if model is not None:
        config = config.model_copy(update={"model": model})
    app = create_app(config, database_url)
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


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m emogen.web.server")
    parser.add_argument("config", type=Path)
    parser.add_argument("--host", default="127.0.0.1")
    parser.add_argument("--port", type=int, default=8000)
    parser.add_argument("--database-url", default=None)
    parser.add_argument("--model", type=Path, default=None)
    parser.add_argument("--log-level", default="warning")
    args = parser.parse_args(argv)
    try:
        run_server(
            args.config,
            host=args.host,
            port=args.port,
            database_url=args.database_url,
            model=args.model,
            log_level=args.log_level,
        )
    except EmoGenError as exc:
        sys.stderr.write(f"error: {exc}\n")
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
