"""The participant API's bodies: requests (strict pydantic models), responses, error bodies.

A step's body is one of the registered commands (:mod:`emogen.tasks.registry`); the session
state is :class:`emogen.study.view.SessionState` (a TypedDict the study core answers with) whose
``view`` is one of the registered tasks' views. pydantic derives their schemas, so the OpenAPI
document and the JS types generated from it (``src/emogen/web/static/api-types.d.ts``) follow
the core's commands and views.
"""

from __future__ import annotations

from typing import Annotated, Any, NotRequired, Optional, Union, get_type_hints

from pydantic import BaseModel, ConfigDict, Field, create_model
from typing_extensions import TypedDict

from emogen.study.enrolment import PARTICIPANT_ID
from emogen.study.records import TrialRecord
from emogen.study.view import SessionState
from emogen.tasks.registry import TASKS, command_names

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
    #: A simulated participant's session (the jsPsych plugin's visual ``simulate()``): the
    #: export's ``participant_source`` says ``simulated``.
    simulated: bool = False


def command_body() -> Any:
    """The step route's body: every registered command (``begin`` and each task's), a union
    keyed by ``command`` (each a strict model: an unknown key or a wrong type is refused)."""
    commands: Any = tuple(command_names().values())
    return Annotated[Union[commands], Field(discriminator="command")]  # noqa: UP007


def state_model() -> Any:
    """The session state as answered (:class:`emogen.study.view.SessionState`) with ``view``
    the union of the registered tasks' views, keyed by ``task``."""
    views: Any = tuple(task.view_type for task in TASKS.values())
    view = Annotated[Union[views], Field(discriminator="task")]  # noqa: UP007
    fields = {**get_type_hints(SessionState), "view": Optional[view]}  # noqa: UP045
    fields["replayed"] = NotRequired[bool]
    return TypedDict("SessionState", fields)  # type: ignore[operator]


def record_model() -> Any:
    """A trial's record as answered (:class:`emogen.study.records.TrialRecord`) with
    ``result`` the union of the registered tasks' results, keyed by ``task``."""
    results: Any = tuple(task.result_type for task in TASKS.values())
    result = Annotated[Union[results], Field(discriminator="task")]  # noqa: UP007
    fields = {**get_type_hints(TrialRecord), "result": Optional[result]}  # noqa: UP045
    return TypedDict("TrialRecord", fields)  # type: ignore[operator]


def created_model(state: Any) -> Any:
    """A session made (or resumed): its secret token, its page and its ``state``."""
    return create_model(
        "Created",
        __doc__="A session made (or resumed): its secret token, its page and its state.",
        token=(str, ...),
        url=(str, ...),
        state=(state, ...),
    )


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
