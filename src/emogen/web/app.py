"""The study server: ``create_app(study_config, database_url)`` builds the FastAPI app.

Participant pages (``/``, ``/s/{token}``) and their JSON API (``/api/sessions``, ``/api/s/{token}/…``),
the researcher dashboard (``/researcher``) and its token-protected API (``/api/researcher/…``).
The core (``emogen.study``) never imports FastAPI; this layer maps its errors to 4xx responses
(:mod:`emogen.web.errors`) and caps request bodies (:mod:`emogen.web.limits`).
"""

from __future__ import annotations

import asyncio
import os
from collections import Counter
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path
from typing import Any

from fastapi import FastAPI
from fastapi.responses import JSONResponse
from fastapi.staticfiles import StaticFiles
from fastapi.templating import Jinja2Templates

from emogen import __version__
from emogen.errors import ConfigError
from emogen.model.face import FaceModel
from emogen.study.check import check_servable
from emogen.study.config import StudyConfig, load_study_config
from emogen.study.failures import SharedBuckets
from emogen.study.sessions import StudyService
from emogen.study.storage import Store, resolve_database_url
from emogen.study.versions import RunningSessions
from emogen.web.assets import ModelGLBs
from emogen.web.embed import add_cors
from emogen.web.errors import install_error_handlers
from emogen.web.exports import remove_stale_downloads
from emogen.web.faces import FacePNGs
from emogen.web.limits import BodyLimit, add_response_headers
from emogen.web.ratelimit import RateLimit, TokenBuckets
from emogen.web.schemas import MAX_BODY_BYTES

HERE = Path(__file__).resolve().parent
RESEARCHER_TOKEN_ENV = "EMOGEN_RESEARCHER_TOKEN"
#: New sessions per client address: 100 at once, then 30 a minute (one every 2 s). A computer
#: room of 60 behind one address (a university NAT) starts within seconds, two rooms within a
#: minute; a script gets 100, then one every 2 s — 1,900 in an hour, not unlimited.
SESSION_LIMIT = RateLimit(burst=100, per_minute=30)
#: Wrong researcher tokens per client address: 10, then one every 6 s — counted in the database,
#: so every worker process (and every server on the database) shares one count.
RESEARCHER_FAILURE_LIMIT = RateLimit(burst=10, per_minute=10)
#: A researcher token's least length and least number of different characters.
MIN_TOKEN_CHARS = 32
MIN_TOKEN_DISTINCT = 10
TOKEN_ADVICE = 'make one with: python -c "import secrets; print(secrets.token_urlsafe(32))"'


def check_researcher_token(token: str) -> None:
    """Refuse a researcher token a brute force could guess: too short, or too few characters."""
    what = f"${RESEARCHER_TOKEN_ENV}"
    if len(token) < MIN_TOKEN_CHARS:
        raise ConfigError(
            f"{what} is {len(token)} characters long; it must be at least {MIN_TOKEN_CHARS} "
            f"(a long random secret): {TOKEN_ADVICE}"
        )
    if len(set(token)) < MIN_TOKEN_DISTINCT:
        raise ConfigError(
            f"{what} has only {len(set(token))} different characters; a random secret has at "
            f"least {MIN_TOKEN_DISTINCT}: {TOKEN_ADVICE}"
        )


def viewer_built() -> bool:
    """Whether the 3D viewer bundle (``npm run build``) exists."""
    return (HERE / "static" / "build" / "study-viewer.js").is_file()


def _lifespan(store: Store) -> Any:
    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        yield
        faces, app.state.faces = app.state.faces, None
        if faces is not None:
            faces.close()
        store.dispose()

    return lifespan


def _routes(app: FastAPI, store: Store, config: StudyConfig) -> None:
    from emogen.web import assets, embed, participant, researcher

    @app.get("/healthz", include_in_schema=False)
    def healthz() -> JSONResponse:
        """200 while participants' steps can be saved; 503 naming why not (a full disk, a
        read-only database; an unreachable one is 503 by the error handler)."""
        store.ping()
        why = store.health_problem()
        body = {"ok": why is None, "study": config.name, "version": __version__}
        return JSONResponse(
            body if why is None else {**body, "problem": why},
            status_code=200 if why is None else 503,
        )

    app.include_router(participant.router)
    app.include_router(participant.session_router())
    app.include_router(embed.router)
    app.include_router(embed.record_router())
    app.include_router(assets.router)
    app.include_router(researcher.router)
    app.mount("/static", StaticFiles(directory=str(HERE / "static")), name="static")


def refuse_unservable(config: StudyConfig) -> None:
    """Blocks participants cannot yet be shown (``TaskBlock.unservable``): refused by name."""
    refused = check_servable(config)
    if refused:
        raise ConfigError("; ".join(f"{f.where}: {f.message}" for f in refused))


def create_app(
    study_config: StudyConfig | str | Path,
    database_url: str | None = None,
    *,
    model: FaceModel | None = None,
    researcher_token: str | None = None,
    session_limit: RateLimit = SESSION_LIMIT,
    researcher_failure_limit: RateLimit = RESEARCHER_FAILURE_LIMIT,
    hsts: bool = False,
    running_sessions: RunningSessions = "refuse",
) -> FastAPI:
    """The study server for one study config.

    database_url : SQLAlchemy URL (default: $EMOGEN_DATABASE_URL, then the config's
      ``database_url``, then an SQLite file in the user data folder).
    model : the face model (default: the config's ``model``, then $EMOGEN_MODEL …).
    researcher_token : default $EMOGEN_RESEARCHER_TOKEN; without one the researcher API is off.
    session_limit : new sessions per client address (429 beyond; ``RateLimit.parse("off")``).
    researcher_failure_limit : wrong researcher tokens per client address (429 beyond),
      counted in the database (shared by every worker process).
    hsts : send Strict-Transport-Security (only when the site is reached over HTTPS only).
    running_sessions : ``end`` ends the unfinished sessions of an earlier design of the study
      (default: refuse to start while there are any; :mod:`emogen.study.versions`).
    """
    from emogen.model import load_model
    from emogen.model.load import model_for_recorded_hash
    from emogen.study.context import recorded_model_hash

    token = (
        researcher_token if researcher_token is not None else os.environ.get(RESEARCHER_TOKEN_ENV)
    )
    if token:  # checked first: a weak token is named before anything loads
        check_researcher_token(token)
    config = (
        study_config
        if isinstance(study_config, StudyConfig)
        else load_study_config(Path(study_config))
    )
    refuse_unservable(config)  # before anything loads
    if model is None:
        model = load_model(config.model, rig=config.rig)
    store = Store(resolve_database_url(database_url, config.database_url))
    store.check_writable()  # a full disk or read-only database: one clear line, at start
    recorded = recorded_model_hash(store, config)
    if recorded is not None:  # a study recorded with an older packaged rig continues with it
        model = model_for_recorded_hash(model, recorded)
    service = StudyService(
        config,
        store,
        model.rig,
        model_name=model.name,
        model_hash=model.model_hash,
        model=model,
        running_sessions=running_sessions,
    )
    app = FastAPI(
        lifespan=_lifespan(store),
        title=f"EmoGen study: {config.name}",
        version=__version__,
        description="Participant and researcher API of an EmoGen study server.",
        docs_url=None,
        redoc_url=None,
    )
    _set_state(
        app,
        config,
        store,
        service,
        model,
        token=token or None,
        session_limit=session_limit,
        researcher_failure_limit=researcher_failure_limit,
    )
    remove_stale_downloads()  # left by a server killed outright (they hold participant data)
    add_cors(app, config.embed_origins)  # innermost: preflights get the security headers too
    add_response_headers(app, hsts=hsts)
    app.add_middleware(BodyLimit, max_bytes=MAX_BODY_BYTES)
    install_error_handlers(app)
    _routes(app, store, config)
    return app


def _set_state(
    app: FastAPI,
    config: StudyConfig,
    store: Store,
    service: StudyService,
    model: FaceModel,
    *,
    token: str | None,
    session_limit: RateLimit,
    researcher_failure_limit: RateLimit,
) -> None:
    """What the routes read from ``app.state``: the study, its store and service, the model and
    its GLB and PNG caches, the researcher token and the rate limits."""
    app.state.config = config
    app.state.store = store
    app.state.service = service
    app.state.model = model
    app.state.researcher_token = token
    app.state.templates = Jinja2Templates(directory=str(HERE / "templates"))
    app.state.viewer = viewer_built()
    identities = config.study_identities()
    app.state.glbs = ModelGLBs(model, identities=identities)
    # no thread or OpenGL context until the first PNG is asked for
    app.state.faces = FacePNGs(
        model, correct=config.correct, identities=identities, framing=config.framing
    )
    app.state.session_buckets = TokenBuckets(session_limit)
    app.state.researcher_failures = SharedBuckets(
        store, burst=researcher_failure_limit.burst, per_minute=researcher_failure_limit.per_minute
    )
    app.state.export_lock = asyncio.Lock()  # one dashboard export at a time
    app.state.link_parameters = Counter()  # URL parameter names of landing pages (web.links)
    app.state.never_matched_warned = False
