"""Participant pages and API. A session is reached only through its secret token."""

from __future__ import annotations

import re
from typing import Annotated, Any
from urllib.parse import quote

import orjson
from fastapi import APIRouter, Body, HTTPException, Path, Query, Request
from fastapi.responses import HTMLResponse, JSONResponse, RedirectResponse, Response

from emogen.study.enrolment import missing_advice
from emogen.study.errors import StudyError
from emogen.study.sessions import StudyService
from emogen.study.view import SessionState
from emogen.web.links import note_parameters, warn_never_matched
from emogen.web.ratelimit import client_key, too_many
from emogen.web.schemas import (
    TOKEN_PATTERN,
    NewSession,
    command_body,
    created_model,
    error_responses,
    state_model,
)

router = APIRouter()

Token = Annotated[
    str,
    Path(pattern=TOKEN_PATTERN, description="The session's secret token (from the session link)."),
]
#: Error codes of the session's steps (a POST with a body).
STEP_ERRORS = error_responses(404, 409, 413, 422, 503)


def _service(request: Request) -> StudyService:
    return request.app.state.service


def _page(request: Request, name: str, **context: Any) -> HTMLResponse:
    cfg = request.app.state.config
    return request.app.state.templates.TemplateResponse(
        request,
        name,
        {"config": cfg, "viewer": request.app.state.viewer, **context},
    )


@router.get("/", response_class=HTMLResponse, include_in_schema=False)
def landing(request: Request) -> HTMLResponse:
    """Consent page; the participant id comes from the URL (``?PROLIFIC_PID=…``). A study with
    ``participant_required`` shows a link without the id a page saying so (400)."""
    cfg = request.app.state.config
    query = request.query_params
    note_parameters(request.app.state.link_parameters, query.keys())
    given = query.get(cfg.participant_param) or query.get("participant")
    if cfg.participant_required and not given:
        response = _page(
            request,
            "error.html",
            heading="Your participant id is missing",
            detail="The link you opened has no participant id.",
            advice=missing_advice(cfg.participant_param),
        )
        response.status_code = 400
        return response
    return _page(request, "landing.html")


LINK_ADVICE = (
    "Check that you opened the whole link you were given (copied links are sometimes cut "
    "short), or open the study link you were given to start.",
    "If you have already started, ask the researcher for your personal session link: it "
    "brings you back to where you were.",
)


def link_error(request: Request, status: int, detail: str) -> HTMLResponse:
    """A participant-facing HTML page for a session link that leads nowhere."""
    response = _page(
        request,
        "error.html",
        heading="This session link is not valid",
        detail=detail,
        advice=LINK_ADVICE,
    )
    response.status_code = status
    return response


@router.get("/s/{link}", response_class=HTMLResponse, include_in_schema=False)
def session_page(request: Request, link: str) -> Response:
    """The session page. ``/s/TOKEN&render=png`` (``&`` typed for ``?``) is sent on to
    ``/s/TOKEN?render=png``; an unknown link gets a friendly HTML page, not JSON."""
    token, amp, rest = link.partition("&")
    if amp:
        query = "&".join(q for q in (rest, request.url.query) if q)
        target = f"/s/{quote(token, safe='')}" + (f"?{query}" if query else "")
        return RedirectResponse(target, status_code=307)
    if not re.fullmatch(TOKEN_PATTERN, token):
        shown = token if len(token) <= 40 else token[:37] + "..."
        return link_error(request, 404, f"“{shown}” is not a session link of this study.")
    try:
        _service(request).state(token)
    except StudyError as exc:  # unknown token (404), a session of an older config (409)
        return link_error(request, exc.status, str(exc))
    return _page(request, "session.html", token=token)


def create_session(request: Request, body: NewSession) -> JSONResponse:
    """Consent given: start a session (or resume this browser's session of the participant).

    Limited per client address (429 with Retry-After beyond the server's session limit)."""
    wait = request.app.state.session_buckets.take(client_key(request))
    if wait > 0:
        raise too_many(wait, "new sessions")
    token, state = _service(request).create_session(
        body.participant_id,
        resume_token=body.resume_token,
        create_key=body.create_key,
        user_agent=request.headers.get("user-agent", ""),
        source="simulated" if body.simulated else None,
    )
    if not body.participant_id:
        warn_never_matched(request.app.state, _service(request))
    return JSONResponse({"token": token, "url": f"/s/{token}", "state": state}, status_code=201)


class _StateResponse(JSONResponse):
    """JSON by orjson: the step's answer carries every shown face's weights, and encoding them
    is a share of the step's CPU (same numbers: shortest round-trip decimals, as Python's)."""

    def render(self, content: Any) -> bytes:
        return orjson.dumps(content)


def _json(state: SessionState) -> JSONResponse:
    """The state as JSON, serialised directly (no per-float encoder pass): the core's
    :class:`SessionState` is the declared ``response_model``, checked by the contract tests."""
    return _StateResponse(state)


def get_state(request: Request, token: Token) -> JSONResponse:
    """Where the session is: stage, progress, the population shown, or the rating asked."""
    return _json(_service(request).state(token))


def session_router() -> APIRouter:
    """The routes whose bodies the registered tasks make: the one step route (its body any
    command the tasks take, or ``begin``, keyed by ``command``), and those answering the
    session's state (its ``view`` any task's view, keyed by ``task``). Made when the app is
    made, so every task registered by then is in them and in the OpenAPI document."""
    routes = APIRouter()
    state = state_model()

    def step(request: Request, token: Token, command: Any) -> JSONResponse:
        """One step of the session: ``begin`` (the instructions read) or a command of the
        current trial's task (a conflict, 409, if its task does not take it)."""
        return _json(_service(request).step(token, command))

    # the body's type is the registry's union of commands, known only now
    step.__annotations__ = {
        "request": Request,
        "token": Token,
        "command": Annotated[command_body(), Body()],
        "return": JSONResponse,
    }
    routes.post(
        "/api/sessions",
        status_code=201,
        response_model=created_model(state),
        responses=error_responses(409, 413, 422, 429, 503),
    )(create_session)
    routes.get(
        "/api/s/{token}/state", response_model=state, responses=error_responses(404, 409, 422, 503)
    )(get_state)
    routes.post("/api/s/{token}/step", response_model=state, responses=STEP_ERRORS)(step)
    return routes


@router.get(
    "/api/s/{token}/faces/{face_id}.png",
    responses={200: {"content": {"image/png": {}}}, **error_responses(404, 409, 422, 503)},
    response_class=Response,
)
async def face_png(
    request: Request,
    token: Token,
    face_id: Annotated[int, Path(ge=0, le=2**31 - 1)],
    trial: Annotated[int | None, Query(ge=0, le=2**31 - 1)] = None,
    attempt: Annotated[int | None, Query(ge=0, le=2**31 - 1)] = None,
) -> Response:
    """A face of the current trial rendered on the server (for browsers without WebGL).

    Face ids count from 0 in every trial and attempt, so the page names both (``?trial=&attempt=``):
    the URL, and so the browser's cached image, is then that trial's face only; a face of a trial
    or attempt that is not the current one is not found."""
    from starlette.concurrency import run_in_threadpool

    service = _service(request)
    weights, identity = await run_in_threadpool(
        service.face_weights, token, face_id, trial, attempt
    )
    faces = request.app.state.faces  # made with the study's identities when the app starts
    if faces is None:
        raise HTTPException(503, "the server is shutting down; try again in a moment")
    png = await faces.render(weights, identity)
    return Response(png, media_type="image/png", headers={"Cache-Control": "private, max-age=3600"})
