"""What a page embedding the study reads (the jsPsych plugin, docs/jspsych.md): the study's
blocks, and a trial's record (session id, seeds, final face). Reaching them from another site
takes that site's origin in the config's ``embed_origins`` (:func:`add_cors`)."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, FastAPI, Path, Request
from fastapi.middleware.cors import CORSMiddleware

from emogen.study.records import StudyInfo, TrialRecord
from emogen.web.participant import Token, _service
from emogen.web.schemas import error_responses, record_model

router = APIRouter()


@router.get("/api/study", response_model=StudyInfo, responses=error_responses(503))
def get_study(request: Request) -> StudyInfo:
    """The study's name, blocks (task and trials of each) and the names of a face's weights."""
    return _service(request).study_info()


def get_trial_record(
    request: Request, token: Token, position: Annotated[int, Path(ge=0, le=100_000)]
) -> TrialRecord:
    """A trial of the session as recorded: the researcher's session id, the trial's and the
    session's seeds (decimal strings), and, once done, its final face's id and weights."""
    return _service(request).trial_record(token, position)


def record_router() -> APIRouter:
    """The trial record's route: its ``result`` is any registered task's, keyed by ``task``
    (made when the app is made, so every task registered by then is in its schema)."""
    routes = APIRouter()
    routes.get(
        "/api/s/{token}/trials/{position}",
        response_model=record_model(),
        responses=error_responses(404, 409, 422, 503),
    )(get_trial_record)
    return routes


def add_cors(app: FastAPI, origins: tuple[str, ...]) -> None:
    """Pages of exactly these origins may call the API (GET, POST with a JSON body; no cookies,
    no credentials: a session is its token). None: no CORS headers at all, the default."""
    if origins:
        app.add_middleware(
            CORSMiddleware,
            allow_origins=list(origins),
            allow_methods=["GET", "POST"],
            allow_headers=["Content-Type"],
            # the page tells a compressed face model's length from its size (the loading bar)
            expose_headers=["Content-Encoding"],
            allow_credentials=False,
            max_age=600,
        )
