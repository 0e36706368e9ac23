"""Engine states on disk: their schemas, and the GA stream and solver each was recorded with.

An engine state ``emogen.ga.engine/4`` records the GA's random stream (``stream``,
:mod:`emogen.ga.draws`), the eq. 5 collision solver its faces were corrected with
(``collision_solver``; ``null`` without a corrector) and the engine's attempt counter
(``attempt``, also in every selection and population). An older EmoGen refuses such a state
rather than draw or correct its faces another way.

``/1`` states were recorded before the GA was written once over runs: stream 1, collision
solver 1, and the attempt counter under its old name ``trial``. :func:`state_data` reads them
as ``/4`` states with those values.
"""

from __future__ import annotations

from typing import Any

import orjson

from emogen.config import GAConfig, validate_config
from emogen.errors import ConfigError
from emogen.ga.draws import CURRENT_STREAM, check_stream

STATE_SCHEMA = "emogen.ga.engine/4"
#: needed by tests/study/test_recorded_before.py::test_recorded_study_replays_exactly and
#: ::test_a_session_recorded_mid_trial_continues_and_replays (tests/data/study_stream1.sqlite)
SCHEMA_1 = "emogen.ga.engine/1"
STATE_SCHEMAS = (SCHEMA_1, STATE_SCHEMA)


def state_data(state: str | dict[str, Any]) -> dict[str, Any]:
    """A stored engine state as a ``/4`` dict (JSON text parsed, a ``/1`` state read as
    ``/4``; a bad text or an unknown schema is a ConfigError)."""
    try:
        data = orjson.loads(state) if isinstance(state, str) else dict(state)
    except orjson.JSONDecodeError as exc:
        raise ConfigError(f"engine state is not valid JSON: {exc}") from None
    schema = data.get("schema") if isinstance(data, dict) else None
    if schema not in STATE_SCHEMAS:
        raise ConfigError(
            f"engine state schema must be one of {list(STATE_SCHEMAS)}; got {schema!r}"
        )
    return _from_schema_1(data) if schema == SCHEMA_1 else data


def _from_schema_1(data: dict[str, Any]) -> dict[str, Any]:
    """A ``/1`` state as ``/4``: stream 1, solver 1, ``trial`` renamed ``attempt``
    (needed by tests/study/test_recorded_before.py::test_recorded_study_replays_exactly)."""
    out = _attempt_named(data)
    out.update(schema=STATE_SCHEMA, stream=1, collision_solver=1)
    out["selections"] = [_attempt_named(s) for s in data["selections"]]
    for part in ("population", "result"):
        out[part] = None if data[part] is None else _attempt_named(data[part])
    return out


def _attempt_named(d: dict[str, Any]) -> dict[str, Any]:
    if "trial" not in d:
        raise ConfigError(f"engine state /1: a part lacks its 'trial'; got keys {sorted(d)}")
    return {("attempt" if k == "trial" else k): v for k, v in d.items()}  # same key order


def selection_attempt(selection: dict[str, Any]) -> int:
    """The attempt of a recorded selection: ``attempt``, or ``trial`` in a selection list of a
    ``/1`` state (needed by
    tests/study/test_recorded_before.py::test_recorded_selections_replay_with_the_old_key)."""
    if "attempt" in selection:
        return int(selection["attempt"])
    if "trial" in selection:
        return int(selection["trial"])
    raise ConfigError(f"recorded selection must name its attempt; got keys {sorted(selection)}")


def stream_of_state(state: str | dict[str, Any] | None) -> int:
    """The GA stream an engine state was recorded with (1 for ``emogen.ga.engine/1`` states).

    ``None`` (nothing recorded yet) gives the current stream.
    """
    if state is None or state == "":
        return CURRENT_STREAM
    return check_stream(state_data(state).get("stream"))


def collision_solver_of_state(state: str | dict[str, Any] | None) -> int:
    """The eq. 5 solver (:data:`emogen.solvers.SOLVERS`) a corrected trial's state was
    recorded with: its ``collision_solver`` (1 for a ``/1`` state). ``None`` (nothing recorded
    yet), or a state recorded without a corrector, gives the current one."""
    from emogen.solvers import CURRENT_SOLVER, check_solver

    if state is None or state == "":
        return CURRENT_SOLVER
    data = state_data(state)
    if "collision_solver" not in data:
        raise ConfigError("engine state must record its collision_solver (a number or null)")
    recorded = data["collision_solver"]
    if recorded is None:  # recorded by an engine without a corrector
        return CURRENT_SOLVER
    try:
        return check_solver(recorded)
    except ValueError as exc:
        raise ConfigError(f"engine state: {exc}") from None


def genome_of_state(state: str | dict[str, Any] | None) -> Any:
    """The genome (:mod:`emogen.ga.genome`) a trial's state was recorded with: static unless it
    records a dynamic one (``None``, nothing recorded yet: static)."""
    from emogen.ga.genome import genome_of

    if state is None or state == "":
        return genome_of(None)
    return genome_of(state_data(state).get("genome"))


def read_state_header(data: dict[str, Any]) -> tuple[GAConfig, int, int]:
    """(config, seed, stream) of a state read by :func:`state_data`, checked."""
    stream = check_stream(data.get("stream"))
    return validate_config(GAConfig, data["config"], "(engine state)"), data["seed"], stream
