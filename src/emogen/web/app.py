"""The study server: ``create_app(study_config, database_url)`` builds the FastAPI app.

Participant pages (``/``, ``/s/{token}``) and their JSON API (``/api/sessions``, ``/api/s/{token}/…``),
the researcher dashboard (``/researcher``) and its token-protected API (``/api/researcher/…``).
The core (``emogen.study``) never imports FastAPI; this layer maps its errors to 4xx responses.
"""

from __future__ import annotations

import logging
import os
import time
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from fastapi.staticfiles import StaticFiles
from fastapi.templating import Jinja2Templates
from sqlalchemy.exc import IntegrityError, OperationalError

from emogen import __version__
from emogen.errors import EmoGenError, ModelFileError
from emogen.model.face import FaceModel
from emogen.study.config import StudyConfig, load_study_config
from emogen.study.errors import StudyError
from emogen.study.sessions import StudyService
from emogen.study.storage import Store, resolve_database_url
from emogen.web.assets import ModelGLBs
from emogen.web.faces import FacePNGs

log = logging.getLogger("emogen.web")

HERE = Path(__file__).resolve().parent
RESEARCHER_TOKEN_ENV = "EMOGEN_RESEARCHER_TOKEN"


def _status_for(exc: EmoGenError) -> int:
    if isinstance(exc, StudyError):
        return exc.status
    if isinstance(exc, ModelFileError):
        return 503
    return 422  # SelectionError, ConfigError, ShapeError: the request's values break a rule


def _validation_message(exc: RequestValidationError) -> str:
    parts = []
    for err in exc.errors():
        loc = ".".join(str(p) for p in err.get("loc", ()) if p not in ("body",))
        parts.append(f"{loc or 'request'}: {err.get('msg', 'invalid')}")
    return "invalid request: " + "; ".join(parts[:5])


def viewer_built() -> bool:
    """Whether the 3D viewer bundle (``node src/emogen/web/build_study_viewer.mjs``) exists."""
    return (HERE / "static" / "build" / "study-viewer.js").is_file()


def create_app(
    study_config: StudyConfig | str | Path,
    database_url: str | None = None,
    *,
    model: FaceModel | None = None,
    researcher_token: str | None = None,
) -> FastAPI:
    """The study server for one study config.

    database_url : SQLAlchemy URL (default: $EMOGEN_DATABASE_URL, then the config's
      ``database_url``, then an SQLite file in the user data folder).
    model : the face model (default: the config's ``model``, then $EMOGEN_MODEL …).
    researcher_token : default $EMOGEN_RESEARCHER_TOKEN; without one the researcher API is off.
    """
    from emogen.model import load_model

    config = (
        study_config
        if isinstance(study_config, StudyConfig)
        else load_study_config(Path(study_config))
    )
    if model is None:
        model = load_model(config.model, rig=config.rig)
    store = Store(resolve_database_url(database_url, config.database_url))
    service = StudyService(
        config, store, model.rig, model_name=model.name, model_hash=model.model_hash, model=model
    )
    token = (
        researcher_token if researcher_token is not None else os.environ.get(RESEARCHER_TOKEN_ENV)
    )

    @asynccontextmanager
    async def lifespan(_app: FastAPI) -> AsyncIterator[None]:
        yield
        faces, _app.state.faces = _app.state.faces, None
        if faces is not None:
            faces.close()
        store.dispose()

    app = FastAPI(
        lifespan=lifespan,
        title=f"EmoGen study: {config.name}",
        version=__version__,
        description="Participant and researcher API of an EmoGen study server.",
        docs_url=None,
        redoc_url=None,
    )
    app.state.config = config
    app.state.store = store
    app.state.service = service
    app.state.model = model
    app.state.researcher_token = token or None
    app.state.templates = Jinja2Templates(directory=str(HERE / "templates"))
    app.state.viewer = viewer_built()
    identities = config.study_identities()
    app.state.glbs = ModelGLBs(model, identities=identities)
    # no thread or OpenGL context until the first PNG is asked for
    app.state.faces = FacePNGs(model, correct=config.correct, identities=identities)

    @app.middleware("http")
    async def timing(request: Request, call_next: Any) -> Any:
        t0 = time.perf_counter()
        response = await call_next(request)
        ms = (time.perf_counter() - t0) * 1000
        response.headers["Server-Timing"] = f"app;dur={ms:.2f}"
        response.headers["X-Content-Type-Options"] = "nosniff"
        response.headers["Referrer-Policy"] = "no-referrer"
        if request.url.path.startswith("/api/"):
            response.headers["Cache-Control"] = "no-store"
        return response

    @app.exception_handler(EmoGenError)
    async def emogen_error(_request: Request, exc: EmoGenError) -> JSONResponse:
        return JSONResponse({"detail": str(exc)}, status_code=_status_for(exc))

    @app.exception_handler(RequestValidationError)
    async def invalid(_request: Request, exc: RequestValidationError) -> JSONResponse:
        return JSONResponse(
            {"detail": _validation_message(exc), "errors": _safe_errors(exc)}, status_code=422
        )

    @app.exception_handler(IntegrityError)
    async def integrity(_request: Request, _exc: IntegrityError) -> JSONResponse:
        return JSONResponse(
            {"detail": "this step was already recorded by another request; reload the page"},
            status_code=409,
        )

    @app.exception_handler(OperationalError)
    async def busy(_request: Request, exc: OperationalError) -> JSONResponse:
        log.warning("database error: %s", exc)
        return JSONResponse(
            {"detail": "the database is busy; try again in a moment"}, status_code=503
        )

    from emogen.web import assets, participant, researcher

    @app.get("/healthz", include_in_schema=False)
    def healthz() -> dict[str, Any]:
        store.ping()
        return {"ok": True, "study": config.name, "version": __version__}

    app.include_router(participant.router)
    app.include_router(assets.router)
    app.include_router(researcher.router)
    app.mount("/static", StaticFiles(directory=str(HERE / "static")), name="static")

    return app


def _safe_errors(exc: RequestValidationError) -> list[dict[str, Any]]:
    out = []
    for err in exc.errors()[:10]:
        out.append(
            {
                "loc": [str(p) for p in err.get("loc", ())],
                "msg": str(err.get("msg", "")),
                "type": str(err.get("type", "")),
            }
        )
    return out
