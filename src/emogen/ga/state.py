"""Engine states on disk: their schemas, and the GA stream each was recorded with."""

from __future__ import annotations

from typing import Any

import orjson

from emogen.config import GAConfig, validate_config
from emogen.errors import ConfigError
from emogen.ga.draws import CURRENT_STREAM, check_stream

#: Engine states: ``/3`` also records the eq. 5 collision solver (``collision_solver``; an older
#: EmoGen refuses such a state rather than correct its faces with another solver); ``/2`` records
#: the GA's random stream (``stream``); ``/1`` states (made before the GA was written once over
#: runs) have none and continue with stream 1, as they were drawn. ``/1`` and ``/2`` states were
#: corrected with solver 1.
STATE_SCHEMA = "emogen.ga.engine/3"
STATE_SCHEMAS = {"emogen.ga.engine/1": 1, "emogen.ga.engine/2": None, STATE_SCHEMA: None}


def state_data(state: str | dict[str, Any]) -> dict[str, Any]:
    """A stored engine state as a dict (JSON text parsed; a bad text is a ConfigError)."""
    try:
        return orjson.loads(state) if isinstance(state, str) else dict(state)
    except orjson.JSONDecodeError as exc:
        raise ConfigError(f"engine state is not valid JSON: {exc}") from None


def stream_of_state(state: str | dict[str, Any] | None) -> int:
    """The GA stream an engine state was recorded with (1 for ``emogen.ga.engine/1`` states).

    ``None`` (nothing recorded yet) gives the current stream.
    """
    if state is None or state == "":
        return CURRENT_STREAM
    data = state_data(state)
    return state_stream(data)


def state_stream(data: dict[str, Any]) -> int:
    schema = data.get("schema")
    if schema not in STATE_SCHEMAS:
        raise ConfigError(
            f"engine state schema must be one of {sorted(STATE_SCHEMAS)}; got {schema!r}"
        )
    legacy = STATE_SCHEMAS[schema]
    return legacy if legacy is not None else check_stream(data.get("stream"))


def collision_solver_of_state(state: str | dict[str, Any] | None) -> int:
    """The eq. 5 solver (:data:`emogen.solvers.SOLVERS`) a corrected trial's state was
    recorded with: its ``collision_solver``, or 1 for a state recorded before solvers were
    numbered (they all used solver 1). ``None`` (nothing recorded yet) gives the current one."""
    from emogen.solvers import CURRENT_SOLVER, check_solver

    if state is None or state == "":
        return CURRENT_SOLVER
    data = state_data(state)
    recorded = data.get("collision_solver", 1)
    if recorded is None:  # recorded by an engine without a corrector
        return CURRENT_SOLVER
    try:
        return check_solver(recorded)
    except ValueError as exc:
        raise ConfigError(f"engine state: {exc}") from None


def read_state_header(data: dict[str, Any]) -> tuple[GAConfig, int, int]:
    """(config, seed, stream) of a stored state, checked."""
    stream = state_stream(data)
    return validate_config(GAConfig, data["config"], "(engine state)"), data["seed"], stream
