"""A scripted participant: drives a session through the service (or over HTTP) to the end."""

from __future__ import annotations

import itertools
from collections.abc import Callable
from typing import Any

_keys = itertools.count()


def new_key() -> str:
    return f"test-key-{next(_keys):06d}"


#: The step commands by the words the tests call them (``call(kind, body)``).
COMMANDS = {"begin": "begin", "select": "select", "restart": "restart", "rating": "rate",
            "rate": "rate", "categorise": "answer", "answer": "answer"}  # fmt: skip


def command(kind: str, body: dict[str, Any]) -> dict[str, Any]:
    """The step route's body of a test's ``call(kind, body)``."""
    return {"command": COMMANDS[kind], **body}


def do(service: Any, kind: str, token: str, key: str, **fields: Any) -> dict[str, Any]:
    """One step through the service: ``kind`` as :data:`COMMANDS` names it, its key, its fields."""
    return service.step(token, command(kind, {"key": key, **fields}))  # type: ignore[no-any-return]


def choose(state: dict[str, Any], n_others: int = 2) -> tuple[int, list[int]]:
    """Elite: the face at position (generation mod 10); others: the next n_others faces."""
    ids = [f["id"] for f in state["view"]["population"]["faces"]]
    g = state["view"]["generation"]
    k = g % len(ids)
    return ids[k], [ids[(k + j) % len(ids)] for j in range(1, n_others + 1)]


def step_args(state: dict[str, Any]) -> dict[str, int]:
    return {
        "trial": state["progress"]["trial"],
        "attempt": state["trial"]["attempt"],
        "generation": state["view"]["generation"],
    }


def run_to_end(
    state: dict[str, Any],
    call: Callable[[str, dict[str, Any]], dict[str, Any]],
    *,
    stop: Callable[[dict[str, Any]], bool] = lambda s: False,
) -> dict[str, Any]:
    """Drive from ``state`` until done (or ``stop(state)``); ``call(kind, body)`` sends a step."""
    while state["stage"] != "done" and not stop(state):
        if state["stage"] == "instructions":
            state = call("begin", {"key": new_key()})
        elif state["trial"]["task"] == "categorise":
            state = call("categorise", categorise_body(state))
        elif state["trial"]["status"] == "active":
            elite, others = choose(state)
            state = call(
                "select",
                {"key": new_key(), **step_args(state), "elite": elite, "others": others,
                 "response_ms": 1234.5},
            )  # fmt: skip
        else:
            state = call(
                "rating",
                {"key": new_key(), "trial": state["progress"]["trial"], "value": 6,
                 "response_ms": 800.0},
            )  # fmt: skip
    return state


def categorise_body(state: dict[str, Any]) -> dict[str, Any]:
    """An answer to a categorise trial: the label offered at (trial mod labels), the ratings
    asked (4 of 7)."""
    view = state["view"]
    labels = view["labels"]
    return {
        "key": new_key(),
        "trial": state["progress"]["trial"],
        "label": labels[state["progress"]["trial"] % len(labels)],
        "intensity": None if view["intensity"] is None else 4,
        "confidence": None if view["confidence"] is None else 4,
        "response_ms": 900.0,
    }


def service_caller(service: Any, token: str) -> Callable[[str, dict[str, Any]], dict[str, Any]]:
    """``call(kind, body)`` through the service's one step."""

    def call(kind: str, body: dict[str, Any]) -> dict[str, Any]:
        return service.step(token, command(kind, body))  # type: ignore[no-any-return]

    return call


def study_service(config: Any, store: Any, model: Any) -> Any:
    """The study service for ``config`` on ``store``, with the model's correctives (as serve:
    a study recorded with an older packaged rig continues with it)."""
    from emogen.model.load import model_for_recorded_hash
    from emogen.study.context import recorded_model_hash
    from emogen.study.sessions import StudyService

    recorded = recorded_model_hash(store, config)
    model = model if recorded is None else model_for_recorded_hash(model, recorded)
    return StudyService(config, store, model.rig, model_name=model.name,
                        model_hash=model.model_hash, model=model)  # fmt: skip
