"""A selection's GA work done before its write transaction (a speed device: see
docs/study.md, "step CPU", for the figure that keeps it).

The engine is restored from the state this process last stored for the session (or the
database's), told the selection, and its next generation made and corrected — with no lock
held, so other sessions' steps proceed meanwhile. The transaction uses the work only if the
trial's stored state is still the one it started from.
"""

from __future__ import annotations

from dataclasses import dataclass

from sqlalchemy import bindparam, select

from emogen.errors import EmoGenError
from emogen.ga.engine import Engine
from emogen.study.storage import Store
from emogen.study.tables import SessionRow, TrialRow
from emogen.study.trials import TrialEngines

#: The session's current trial if it shows a population: engine state, identity, position,
#: attempt, generation (read without a lock to prepare a selection).
_ACTIVE_TRIAL = (
    select(
        TrialRow.engine_state,
        TrialRow.identity,
        TrialRow.position,
        TrialRow.attempt,
        TrialRow.generation,
    )
    .join(SessionRow, TrialRow.session_id == SessionRow.id)
    .where(
        SessionRow.token == bindparam("token"),
        SessionRow.study_id == bindparam("study_id"),
        SessionRow.stage == "trial",
        TrialRow.position == SessionRow.current_trial,
        TrialRow.status == "active",
        TrialRow.task == "evolve",
    )
)


@dataclass(frozen=True)
class Prepared:
    """A selection's GA work done outside the transaction: the engine state it started from,
    the engine told the selection (its next population made and corrected) and that engine's
    state now (what the transaction stores)."""

    engine_state: str
    engine: Engine
    next_state: str


def prepare_select(
    engines: TrialEngines, store: Store, study_id: int, token: str, *, trial: int, attempt: int,
    generation: int, elite: int, others: list[int],
) -> Prepared | None:  # fmt: skip
    """A selection's GA work (the engine restored, told, the next generation made and
    corrected) done before its write transaction, so that no lock is held meanwhile and
    steps of other sessions (other workers, other threads) proceed in parallel.

    It starts from the state this process last stored for the session, if that is of the
    request's generation (no read: :meth:`TrialEngines.latest`), else from the database's.
    The transaction uses it only if the trial's stored engine state is still the one it was
    computed from (the engine is deterministic: the same state and selection make the same
    generation); otherwise, and for anything unexpected here (another trial or generation
    shown, a selection the engine refuses), it does the work itself and answers as it
    always did. Returns None when there is nothing to prepare.
    """

    state: str | None
    known = engines.latest(token, trial, attempt, generation)  # stored by this process
    if known is not None:
        state, identity = known
    else:
        with store.engine.connect() as conn:  # one plain read, no ORM session
            found = conn.execute(_ACTIVE_TRIAL, {"token": token, "study_id": study_id}).first()
        if found is None:
            return None
        state, identity, position, row_attempt, row_generation = found
        if (position, row_attempt, row_generation) != (trial, attempt, generation):
            return None
    if not state:
        return None
    try:
        engine = engines.restore_state(state, identity)
        engine.tell(elite, others)
        if engine.done:
            engine.result  # noqa: B018 - corrected here, not under the lock
        else:
            engine.ask()
        next_state = engine.to_json()
    except EmoGenError:
        return None
    return Prepared(state, engine, next_state)
