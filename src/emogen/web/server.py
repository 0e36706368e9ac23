"""Run the study server: ``emogen serve STUDY.toml --port 8000`` calls :func:`run_server`.

One worker process (``workers=1``) serves the app in this process. More (``--workers N``, the
default being the number of cores) run uvicorn's worker processes, each with its own app, model
and database connections, sharing the listening socket; the study is checked (model, database,
migration, the study's row) once here before they start, so a broken config fails at once
instead of in every worker. A worker dies with the process that started it (``SIGKILL``ed
with it on Linux), so a killed server leaves no worker holding its port.

The address is checked before anything loads (a port in use, a host this machine does not
have: a clear error at once, not after the model has loaded), and the banner with the links
is printed once the address accepts connections, not before (with several workers a request
sent then waits for the first worker instead of being refused).
"""

from __future__ import annotations

import errno
import json
import os
import signal
import socket
import sys
import threading
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

from emogen.errors import ConfigError, ResourceError

if TYPE_CHECKING:
    from fastapi import FastAPI

#: How the worker processes get their options (JSON; set by :func:`run_server`).
WORKER_OPTIONS_ENV = "EMOGEN_SERVE_WORKER_OPTIONS"
#: Idle keep-alive connections are closed after this many seconds (nginx's default).
KEEP_ALIVE_S = 75
#: How long the banner waits for the address to accept connections (then it is not printed).
LISTEN_WAIT_S = 120.0


def default_workers() -> int:
    """The number of cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def _app(options: dict[str, Any]) -> FastAPI:
    from emogen.study.config import load_study_config
    from emogen.web.app import SESSION_LIMIT, create_app
    from emogen.web.ratelimit import RateLimit

    config = load_study_config(Path(options["config"]))
    if options.get("model") is not None:
        config = config.model_copy(update={"model": Path(options["model"])})
    try:
        text = options.get("session_limit")
        limit = SESSION_LIMIT if text is None else RateLimit.parse(text)
    except ValueError as exc:
        raise ConfigError(f"--session-limit: {exc}") from None
    app = create_app(
        config,
        options.get("database_url"),
        session_limit=limit,
        hsts=bool(options.get("hsts")),
        running_sessions=options.get("running_sessions") or "refuse",
    )
    # every identity's face model (GLB) on disk before anyone arrives: made on first request,
    # the page would wait for it at the switch to a new identity (20–30 s on a loaded
    # machine: benchmarks/bench_design_walk.py); workers then read the parent's files
    app.state.glbs.make_all()
    return app


def _die_with_parent(parent: int) -> None:
    """Linux: this process gets SIGKILL when the process that started it dies."""
    if sys.platform != "linux":  # pragma: no cover
        return
    import ctypes

    pr_set_pdeathsig = 1
    ctypes.CDLL(None, use_errno=True).prctl(pr_set_pdeathsig, int(signal.SIGKILL))
    if os.getppid() != parent:  # the parent died before the line above
        os._exit(1)


def worker_app() -> FastAPI:
    """The app of one worker process (uvicorn's app factory; options from the environment)."""
    options = json.loads(os.environ[WORKER_OPTIONS_ENV])
    _die_with_parent(int(options["parent"]))
    return _app(options)


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
    workers: int | None = None,
    running_sessions: str = "refuse",
    header_timeout: float | None = None,
    body_timeout: float | None = None,
) -> None:
    """Load the study, open (and migrate) the database, serve until interrupted.

    No access log: session links carry their secret token in the path. ``session_limit`` is a
    :meth:`RateLimit.parse` text (default 30/min, burst 100 per client address; counted per worker
    process); ``hsts`` sends HSTS; ``workers``: worker processes (default: the cores);
    ``running_sessions``: ``end`` ends the unfinished sessions of an earlier design of the study
    (default: refuse to start while there are any); ``header_timeout``: seconds a request's
    headers may take to arrive (408 beyond; :mod:`emogen.web.protocol`, default 15);
    ``body_timeout``: seconds its body may take after them (408 beyond;
    :class:`emogen.web.limits.BodyLimit`, default 20).
    """
    import uvicorn

    from emogen.web.limits import BODY_TIMEOUT_ENV
    from emogen.web.protocol import HEAD_TIMEOUT_ENV, PROTOCOL

    n_workers = default_workers() if workers is None else workers
    if n_workers < 1:
        raise ConfigError(f"--workers must be at least 1; got {n_workers}")
    check_address(host, port)
    if header_timeout is not None:
        if not 0 < header_timeout <= 600:
            raise ConfigError(f"--header-timeout must be in (0, 600] seconds; got {header_timeout}")
        os.environ[HEAD_TIMEOUT_ENV] = str(header_timeout)  # the workers read it
    if body_timeout is not None:
        if not 0 < body_timeout <= 600:
            raise ConfigError(f"--body-timeout must be in (0, 600] seconds; got {body_timeout}")
        os.environ[BODY_TIMEOUT_ENV] = str(body_timeout)
    options = {
        "config": str(Path(config_path).resolve()),
        "model": None if model is None else str(Path(model).resolve()),
        "database_url": database_url,
        "session_limit": session_limit,
        "hsts": hsts,
        "running_sessions": running_sessions,
        "parent": os.getpid(),
    }
    app = _loaded_app(options, announce)  # the whole study checked here, once
    stopped = threading.Event()  # the banner stops waiting for the address
    if announce:
        _announce_when_listening(_banner(app, host, port, n_workers), host, port, stopped)
    common: dict[str, Any] = {
        "host": host,
        "port": port,
        "log_level": log_level,
        "access_log": False,
        "timeout_graceful_shutdown": 3,
        # request heads bounded in size (431) and read time (408): uvicorn's own are not
        "http": PROTOCOL,
        # participants pause 1–20 s between steps: a 5 s keep-alive (uvicorn's default) closes
        # most connections between steps, and a step sent as the server closes it fails
        "timeout_keep_alive": KEEP_ALIVE_S,
    }
    try:
        if n_workers == 1:
            uvicorn.run(app, **common)
            return
        app.state.store.dispose()
        del app
        os.environ[WORKER_OPTIONS_ENV] = json.dumps(options)
        uvicorn.run("emogen.web.server:worker_app", factory=True, workers=n_workers, **common)
    finally:
        stopped.set()


def _loaded_app(options: dict[str, Any], announce: bool) -> FastAPI:
    """:func:`_app`, saying what takes the time: loading the model and the study, and on the
    first start after an install compiling the face correction (the study's probe generation
    is corrected while the app is made, so no participant's first step waits for it)."""
    if not announce:
        return _app(options)
    sys.stdout.write(
        "Loading the study and the face model (the first start after an install may also compile "
        "the face correction and make each identity's 3D model: up to a minute or two) ... "
    )
    sys.stdout.flush()
    start = time.perf_counter()
    try:
        app = _app(options)
    except BaseException:
        sys.stdout.write("\n")  # the error follows on a line of its own
        raise
    sys.stdout.write(f"ready ({time.perf_counter() - start:.1f} s)\n")
    return app


def check_address(host: str, port: int) -> None:
    """Refuse an address this machine cannot listen on (the server binds it again itself)."""
    hint = "choose another with --port"
    if not 1 <= port <= 65535:
        raise ConfigError(f"--port must be in 1..65535; got {port}")
    try:
        with socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET) as sock:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # as uvicorn binds
            sock.bind((host, port))
    except OSError as exc:
        if exc.errno == errno.EADDRINUSE:
            why = f"port {port} is in use (another server, or another `emogen serve`?): {hint}"
        elif exc.errno == errno.EACCES:
            why = f"permission denied (ports below 1024 need administrator rights): {hint}"
        else:
            why = f"{exc.strerror or exc} (check --host '{host}' and --port)"
        raise ResourceError(f"cannot listen on {host}:{port}: {why}") from None


def _announce_when_listening(banner: str, host: str, port: int, stop: threading.Event) -> None:
    """Print ``banner`` (from a thread) once ``host:port`` accepts connections; not at all if
    ``stop`` is set first or it does not within ``LISTEN_WAIT_S``."""
    target = {"0.0.0.0": "127.0.0.1", "::": "::1", "": "127.0.0.1"}.get(host, host)

    def wait() -> None:
        deadline = time.monotonic() + LISTEN_WAIT_S
        while not stop.is_set() and time.monotonic() < deadline:
            try:
                with socket.create_connection((target, port), timeout=1.0):
                    pass
            except OSError:
                stop.wait(0.05)
                continue
            sys.stdout.write(banner)
            sys.stdout.flush()
            return

    threading.Thread(target=wait, name="emogen-banner", daemon=True).start()


def _banner(app: FastAPI, host: str, port: int, workers: int) -> str:
    from emogen.study.length import session_length

    config = app.state.config
    shown = "localhost" if host in ("127.0.0.1", "0.0.0.0", "::") else host
    return (
        f"EmoGen study '{config.name}' ({app.state.service.n_trials} trials), data in "
        f"{app.state.store.describe()}, {workers} worker process{'es' if workers > 1 else ''}\n"
        f"  participants open:    http://{shown}:{port}/?{config.participant_param}=PARTICIPANT_ID"
        f"{' (required)' if config.participant_required else ''}\n"
        f"  {session_length(config.conditions(), config.ga.generations).explained()}\n"
        f"  researcher dashboard: http://{shown}:{port}/researcher"
        f"{'' if app.state.researcher_token else '  (set EMOGEN_RESEARCHER_TOKEN to enable)'}\n"
        "  stop with Ctrl-C\n"
    )
