"""The web layer's error answers: every error is JSON ``{"detail": str}`` (a 422 adds ``errors``).

:func:`install_error_handlers` maps the core's :class:`~emogen.errors.EmoGenError` to 4xx/503,
request validation to 422 and database conflicts / busy databases to 409 / 503.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exception_handlers import http_exception_handler
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse, Response
from sqlalchemy.exc import DBAPIError, IntegrityError, OperationalError
from starlette.exceptions import HTTPException as StarletteHTTPException

from emogen.errors import EmoGenError, ModelFileError
from emogen.study.errors import StudyError
from emogen.study.storage import storage_problem
from emogen.web.schemas import FieldError, InvalidRequest, Problem

log = logging.getLogger("emogen.web")


def status_for(exc: EmoGenError) -> int:
    if isinstance(exc, StudyError):
        return exc.status
    if isinstance(exc, ModelFileError):
        return 503
    return 422  # SelectionError, ConfigError, ShapeError: the request's values break a rule


def invalid_request(exc: RequestValidationError) -> InvalidRequest:
    """The 422 body: one message naming the bad values, and the first ten broken rules."""
    errors = [
        FieldError(
            loc=[str(p) for p in err.get("loc", ())],
            msg=str(err.get("msg", "")),
            type=str(err.get("type", "")),
        )
        for err in exc.errors()[:10]
    ]
    parts = []
    for err, raw in zip(errors[:5], exc.errors()[:5], strict=True):
        loc = ".".join(p for p in err.loc if p != "body")
        parts.append(f"{loc or 'request'}: {err.msg or 'invalid'}{_got(raw)}")
    return InvalidRequest(detail="invalid request: " + "; ".join(parts), errors=errors)


def _got(err: Mapping[str, Any]) -> str:
    """``; got <value>`` for a short, plain bad value (never a whole body or a missing one)."""
    if err.get("type") == "missing" or "input" not in err:
        return ""
    value = err["input"]
    if isinstance(value, dict | list) or value is None:
        return ""
    text = repr(value)
    return f"; got {text}" if len(text) <= 60 else f"; got {text[:57]}..."


def problem(status: int, detail: str) -> JSONResponse:
    return JSONResponse(Problem(detail=detail).model_dump(), status_code=status)


#: Paths whose errors stay JSON; any other unknown address is a link a person typed or was given.
_MACHINE_PATHS = ("/api/", "/static/", "/openapi.json", "/healthz")


def install_error_handlers(app: FastAPI) -> None:
    @app.exception_handler(StarletteHTTPException)
    async def not_found(request: Request, exc: StarletteHTTPException) -> Response:
        """An unknown page address (``/s/``, ``/S/TOKEN``, ``/s/TOKEN/x``) gets the link error
        page the docs promise, never raw JSON; the API's errors stay JSON."""
        if exc.status_code == 404 and not request.url.path.startswith(_MACHINE_PATHS):
            from emogen.web.participant import link_error

            shown = (
                request.url.path if len(request.url.path) <= 40 else request.url.path[:37] + "..."
            )
            return link_error(request, 404, f"“{shown}” is not a session link of this study.")
        return await http_exception_handler(request, exc)

    @app.exception_handler(EmoGenError)
    async def emogen_error(_request: Request, exc: EmoGenError) -> JSONResponse:
        return problem(status_for(exc), str(exc))

    @app.exception_handler(RequestValidationError)
    async def invalid(_request: Request, exc: RequestValidationError) -> JSONResponse:
        return JSONResponse(invalid_request(exc).model_dump(), status_code=422)

    @app.exception_handler(IntegrityError)
    async def integrity(_request: Request, _exc: IntegrityError) -> JSONResponse:
        return problem(409, "this step was already recorded by another request; reload the page")

    @app.exception_handler(DBAPIError)
    async def database(_request: Request, exc: DBAPIError) -> JSONResponse:
        """A full disk or a read-only database is said as such (nothing can be saved until
        the researcher acts); other operational errors are a busy database."""
        why = storage_problem(exc)
        if why is not None:
            log.error("the study database cannot save: %s (%s)", why, exc.orig)
            return problem(503, f"{why}: nothing can be saved now; please tell the researcher")
        if not isinstance(exc, OperationalError):
            raise exc
        log.warning("database error: %s", exc)
        return problem(503, "the database is busy; try again in a moment")
