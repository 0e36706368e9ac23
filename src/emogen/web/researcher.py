"""Researcher dashboard and API, behind ``Authorization: Bearer $EMOGEN_RESEARCHER_TOKEN``."""

from __future__ import annotations

import hmac
from typing import Annotated, Any

from fastapi import APIRouter, Depends, Path, Query, Request
from fastapi.responses import HTMLResponse, Response
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer
from pydantic import BaseModel, Field

from emogen.study.dashboard import block_notes, design_notes, overview
from emogen.study.errors import Forbidden
from emogen.study.export import TABLES, study_status
from emogen.study.export_stream import parse_since
from emogen.study.progress import progress_as_shown
from emogen.web.exports import MEDIA_TYPES, export_table_file
from emogen.web.links import never_matched_warning
from emogen.web.ratelimit import client_key, too_many
from emogen.web.schemas import error_responses

router = APIRouter()
DISABLED = (
    "the researcher API is disabled on this server: start it with EMOGEN_RESEARCHER_TOKEN set "
    "(a long random secret) to use the dashboard"
)
_bearer = HTTPBearer(auto_error=False, description="EMOGEN_RESEARCHER_TOKEN")


def researcher(
    request: Request,
    credentials: Annotated[HTTPAuthorizationCredentials | None, Depends(_bearer)],
) -> None:
    """The researcher token checked in constant time; wrong ones are limited per client address
    (429 once the failure limit is spent, before the token is even compared). Never logged."""
    expected = request.app.state.researcher_token
    if not expected:
        raise Forbidden(DISABLED)
    failures = request.app.state.researcher_failures
    client = client_key(request)
    wait = failures.wait(client)
    if wait > 0:
        raise too_many(wait, "wrong researcher tokens")
    given = credentials.credentials if credentials is not None else ""
    if not hmac.compare_digest(given.encode(), expected.encode()):
        failures.take(client)
        raise Forbidden("researcher endpoints need 'Authorization: Bearer <researcher token>'")


Researcher = Annotated[None, Depends(researcher)]


@router.get("/researcher", response_class=HTMLResponse, include_in_schema=False)
def dashboard(request: Request) -> HTMLResponse:
    """The dashboard page (it asks for the token and reads the API)."""
    return request.app.state.templates.TemplateResponse(
        request,
        "researcher.html",
        {
            "config": request.app.state.config,
            "viewer": False,
            "disabled": None if request.app.state.researcher_token else DISABLED,
            "tables": TABLES,
        },
    )


@router.get("/api/researcher/status", responses=error_responses(403, 429, 503))
def status(request: Request, _auth: Researcher) -> dict[str, Any]:
    """Progress of every study in the database, and of this study's sessions; this study's
    durations, progress per condition, Latin-square row counts, estimated session length,
    and warnings (a participant URL parameter no link carried)."""
    store = request.app.state.store
    service = request.app.state.service
    ctx = service.ctx
    warning = never_matched_warning(request.app.state, service)
    return {
        "study": ctx.config.name,
        "study_id": ctx.study_id,
        "studies": study_status(store),
        "sessions": progress_as_shown(store, ctx.study_id),
        **overview(store, ctx.config, ctx.accepted),
        "warnings": ([] if warning is None else [warning])
        + design_notes(ctx.config)
        + block_notes(store, ctx.config, ctx.accepted),
    }


class ResumeLink(BaseModel):
    """A participant's personal session link (the same link each time it is asked for)."""

    participant_id: str
    path: str = Field(description="/s/<token>: the session page, relative to the server.")
    url: str = Field(description="The link as this request reached the server.")


@router.get(
    "/api/researcher/participants/{participant_id}/link",
    response_model=ResumeLink,
    responses=error_responses(403, 404, 422, 429, 503),
)
def resume_link(
    request: Request,
    _auth: Researcher,
    participant_id: Annotated[str, Path(max_length=128, description="The participant id.")],
) -> ResumeLink:
    """The participant's personal session link, to give back to them (another browser or
    device reaches the session only with it)."""
    token = request.app.state.service.participant_token(participant_id)
    path = f"/s/{token}"
    return ResumeLink(
        participant_id=participant_id, path=path, url=str(request.base_url).rstrip("/") + path
    )


TableName = Annotated[str, Path(pattern="^(" + "|".join(TABLES) + ")$")]
Since = Annotated[
    str | None,
    Query(
        max_length=64,
        description="Incremental: only the sessions completed from this ISO 8601 time to "
        "a minute ago (see docs/study.md).",
    ),
]


async def _download(request: Request, table: str, since: str | None, fmt: str) -> Response:
    if since is not None:
        parse_since(since)  # a bad time is a 422 naming it, before any work
    state = request.app.state
    return await export_table_file(
        state.export_lock, state.store.url, state.service.ctx.config.name, table, since, fmt
    )


@router.get(
    "/api/researcher/export/{table}.csv",
    responses={200: {"content": {"text/csv": {}}}, **error_responses(403, 422, 429, 503)},
    response_class=Response,
)
async def export_csv(
    request: Request, _auth: Researcher, table: TableName, since: Since = None
) -> Response:
    """One export table of this study as CSV, written by a separate low-priority process in
    bounded memory (participants' requests go first) and streamed."""
    return await _download(request, table, since, "csv")


@router.get(
    "/api/researcher/export/{table}.parquet",
    responses={
        200: {"content": {MEDIA_TYPES["parquet"]: {}}},
        **error_responses(403, 422, 429, 503),
    },
    response_class=Response,
)
async def export_parquet(
    request: Request, _auth: Researcher, table: TableName, since: Since = None
) -> Response:
    """One export table of this study as Parquet (the provenance in its metadata), written
    as the CSV is."""
    return await _download(request, table, since, "parquet")
