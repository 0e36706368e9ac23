"""The participant API's bodies: requests (strict pydantic models), responses, error bodies.

The session state is :class:`emogen.study.view.SessionState` (a TypedDict the study core
answers with); pydantic derives its schema, so the OpenAPI document and the JS types generated
from it (``src/emogen/web/static/api-types.d.ts``) follow the core's view.
"""

from __future__ import annotations

from typing import Annotated, Any

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field

from emogen.study.enrolment import PARTICIPANT_ID
from emogen.study.view import SessionState

#: A client-made key per step (e.g. a UUID); the same key again is the same step.
StepKey = Annotated[str, Field(pattern=r"^[A-Za-z0-9_-]{8,64}$")]


def _whole_number(value: Any) -> Any:
    """JSON Schema counts 3.0 as an integer: take it as 3 (3.5 stays a float and is refused)."""
    return int(value) if isinstance(value, float) and value.is_integer() else value


Index = Annotated[int, Field(ge=0, le=100_000), BeforeValidator(_whole_number)]
FaceId = Annotated[int, Field(ge=0, le=2**31 - 1), BeforeValidator(_whole_number)]
Millis = Annotated[float, Field(ge=0, le=86_400_000, allow_inf_nan=False)]
TOKEN_PATTERN = r"^[A-Za-z0-9_-]{16,64}$"
#: The largest request body the API reads (bytes); a larger one is answered 413.
MAX_BODY_BYTES = 64 * 1024


class _Body(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True)


class NewSession(_Body):
    #: The URL's participant id (empty or absent: one is generated). The schema states the
    #: core's rule (``PARTICIPANT_ID``); the core checks it and names the rule in its 422.
    participant_id: (
        Annotated[
            str,
            Field(max_length=128, json_schema_extra={"pattern": f"^$|^{PARTICIPANT_ID.pattern}$"}),
        ]
        | None
    ) = None
    #: The token this browser holds for the participant's session, to resume it.
    resume_token: Annotated[str, Field(pattern=TOKEN_PATTERN)] | None = None
    #: A random key the page makes once, before its first try, and sends with every retry: a
    #: retried create (its answer lost) then gets the same session, not a conflict.
    create_key: Annotated[str, Field(pattern=r"^[A-Za-z0-9_-]{16,64}$")] | None = None


class Begin(_Body):
    key: StepKey


class Selection(_Body):
    key: StepKey
    trial: Index
    attempt: Index
    generation: Index
    elite: FaceId
    others: Annotated[list[FaceId], Field(max_length=100)] = []
    response_ms: Millis | None = None
    #: Page's time from receiving this population to all its faces drawn (the first faces a
    #: freshly opened page shows: from the page's start, so page, model and textures); the
    #: server's ``server_response_ms`` excludes it.
    load_ms: Millis | None = None


class Restart(_Body):
    key: StepKey
    trial: Index
    attempt: Index
    generation: Index
    response_ms: Millis | None = None
    #: Page's time from receiving this population to all its faces drawn (the first faces a
    #: freshly opened page shows: from the page's start, so page, model and textures); the
    #: server's ``server_response_ms`` excludes it.
    load_ms: Millis | None = None


class Rating(_Body):
    key: StepKey
    trial: Index
    value: Annotated[int, Field(ge=1, le=11), BeforeValidator(_whole_number)]
    response_ms: Millis | None = None


class Categorisation(_Body):
    """The answer to a categorise trial's face: one of the labels it offered (or ``none`` where
    the block offers "none of these"), and the intensity / confidence ratings the block asks."""

    key: StepKey
    trial: Index
    label: Annotated[str, Field(min_length=1, max_length=64)]
    intensity: Annotated[int, Field(ge=1, le=11), BeforeValidator(_whole_number)] | None = None
    confidence: Annotated[int, Field(ge=1, le=11), BeforeValidator(_whole_number)] | None = None
    response_ms: Millis | None = None
    #: Page's time from receiving the face to it drawn (see ``Selection.load_ms``).
    load_ms: Millis | None = None


class Created(BaseModel):
    """A session made (or resumed): its secret token, its page and its state."""

    token: str
    url: str
    state: SessionState


class Problem(BaseModel):
    """An error: what went wrong and what to do, in one sentence for people."""

    detail: str


class FieldError(BaseModel):
    """One rule a request broke: where (``loc``), what (``msg``) and its kind (``type``)."""

    loc: list[str]
    msg: str
    type: str


class InvalidRequest(Problem):
    """A request whose values break a rule (HTTP 422): the message, then each broken rule."""

    errors: list[FieldError] = []


ERRORS: dict[int, tuple[type[BaseModel], str]] = {
    403: (Problem, "Researcher endpoints without the right token (or disabled)."),
    404: (Problem, "No session with this token, or no such face now."),
    409: (Problem, "The request does not fit the session now (stale page, reused step key)."),
    413: (Problem, f"The request body is larger than {MAX_BODY_BYTES} bytes."),
    422: (InvalidRequest, "The request's values break a rule (the message names the value)."),
    429: (Problem, "Too many requests from this address; wait Retry-After seconds."),
    503: (Problem, "The server is busy or shutting down; try again in a moment."),
}
_RETRY_AFTER = {
    "Retry-After": {
        "description": "Seconds to wait before trying again.",
        "schema": {"type": "integer", "minimum": 1},
    }
}


def error_responses(*codes: int) -> dict[int | str, dict[str, Any]]:
    """OpenAPI ``responses`` entries of these error codes, each with its body model."""
    return {
        code: {
            "model": ERRORS[code][0],
            "description": ERRORS[code][1],
            **({"headers": _RETRY_AFTER} if code == 429 else {}),
        }
        for code in codes
    }
