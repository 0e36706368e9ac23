"""The study's steps: each one transaction, committed before it is answered, and idempotent.

A session goes consent (its creation) → instructions → trial 1 … T → done. In a trial the GA
engine shows generations 0 … G; every shown population is stored when it is made, every
selection / restart / rating with its timestamps and response times. The engine's JSON state is
kept with the trial, so a reload or a server restart resumes exactly where the participant was.

Every state-changing step carries an idempotency key: the same key again returns the current
state without doing anything (a double click, a retried request); a key reused for a different
request, or a request for a generation that is no longer shown, is a conflict (HTTP 409).
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from datetime import datetime

from sqlalchemy import Connection, bindparam, select
from sqlalchemy.orm import Session
from sqlalchemy.orm.attributes import set_committed_value

from emogen.errors import EmoGenError, SelectionError
from emogen.ga.engine import Engine
from emogen.study.context import StudyContext
from emogen.study.errors import SessionNotFound, StepConflict
from emogen.study.queries import (
    Executor,
    SessionRecord,
    ShownAt,
    StepRead,
    StepTaken,
    TrialRecord,
    last_selection_time,
    n_trials,
    session_by_token,
    step_read,
    step_with_key,
    trial_at,
)
from emogen.study.storage import Store
from emogen.study.tables import (
    RatingRow,
    SessionRow,
    TrialRow,
    as_utc,
    dumps,
    utcnow,
)
from emogen.study.trials import TrialEngines, store_population
from emogen.study.view import SessionState, ShownPopulation, session_state
from emogen.study.writes import INSERT_RESTART, INSERT_SELECTION, advance_trial, record_step

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
    )
)
#: What a step's request held (hashed to tell a replayed key from a reused one).
Payload = Mapping[str, int | float | list[int] | None]
#: A step's work on the locked session; returns the population it has just shown, if any.
Action = Callable[[Session, SessionRow], ShownPopulation | None]
#: The same on plain rows (:meth:`SessionSteps.run_plain`): also the trial as the step left it.
PlainAction = Callable[[Connection, StepRead], tuple[ShownPopulation | None, TrialRecord]]


def request_hash(kind: str, payload: Payload) -> str:
    text = kind + ":" + json.dumps(payload, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def elapsed_ms(later: datetime, earlier: datetime | None) -> float:
    """Milliseconds from ``earlier`` to ``later`` (0 when there is no earlier time)."""
    e = as_utc(earlier)
    later_utc = as_utc(later)
    if e is None or later_utc is None:
        return 0.0
    return max(0.0, (later_utc - e).total_seconds() * 1000.0)


@dataclass(frozen=True)
class Prepared:
    """A selection's GA work done outside the transaction: the engine state it started from,
    the engine told the selection (its next population made and corrected) and that engine's
    state now (what the transaction stores)."""

    engine_state: str
    engine: Engine
    next_state: str


@dataclass(frozen=True)
class Timing:
    """What the page reports of a step: ``response_ms`` (faces visible → answer) and
    ``load_ms`` (population received → faces drawn: for generation 0 the page, model and
    texture loading). The server's time excludes ``load_ms``: see :func:`server_ms`."""

    response_ms: float | None = None
    load_ms: float | None = None


def server_ms(later: datetime, shown_at: datetime | None, load_ms: float | None) -> float:
    """``server_response_ms``: from the population stored to the answer received, less the
    page's reported loading time (so generation 0 does not count page and model loading)."""
    return max(0.0, elapsed_ms(later, shown_at) - (load_ms or 0.0))


class SessionSteps:
    """The transitions of a session: begin, select, restart, rate (each under a step key)."""

    def __init__(self, ctx: StudyContext, store: Store, engines: TrialEngines) -> None:
        self.ctx = ctx
        self.store = store
        self.engines = engines

    def run(
        self, token: str, kind: str, key: str, payload: Payload, action: Action
    ) -> SessionState:
        """Do ``action`` once per key, in one transaction; answer the session's state."""
        digest = request_hash(kind, payload)

        def work(db: Session) -> SessionState:
            sess = session_by_token(db, token, self.ctx.study_id, lock=True)
            replayed = self._replayed(db, db, sess, kind, key, digest)
            if replayed is not None:
                return replayed
            shown = action(db, sess)
            db.flush()  # what the step changed through the ORM
            self.engines.remember(token, None if shown is None else shown.trial)
            set_committed_value(sess, "updated_at", record_step(db, sess.id, kind, key, digest))
            return session_state(db, self.ctx.config, sess, shown)

        return self.store.transact(work)

    def run_plain(
        self, token: str, kind: str, key: str, payload: Payload, action: PlainAction
    ) -> SessionState:
        """:meth:`run` for the steps of a shown generation (select, restart): the session, the
        key's step, the trial and its shown population read by one statement, and written by
        plain statements on the transaction's connection — the ORM's loading and unit of work
        cost a selection more CPU than its statements."""
        digest = request_hash(kind, payload)

        def work(db: Session) -> SessionState:
            conn = db.connection()
            read = step_read(conn, token, self.ctx.study_id, key)
            if read.taken is not None:
                return self._replay(db, read.session, read.taken, kind, key, digest)
            shown, trial = action(conn, read)
            record_step(conn, read.session.id, kind, key, digest)
            self.engines.remember(token, trial)
            return session_state(db, self.ctx.config, read.session, shown, trial)

        return self.store.transact(work)

    def _replayed(
        self, db: Session, ex: Executor, sess: SessionRow | SessionRecord, kind: str, key: str,
        digest: str,
    ) -> SessionState | None:  # fmt: skip
        """The current state if this key's step was already taken (a conflict if the key was
        used for another request); None for a new step."""
        done = step_with_key(ex, sess.id, key)
        return None if done is None else self._replay(db, sess, done, kind, key, digest)

    def _replay(
        self, db: Session, sess: SessionRow | SessionRecord, done: StepTaken, kind: str, key: str,
        digest: str,
    ) -> SessionState:  # fmt: skip
        """The answer to a key already used: the current state (the same request again), or a
        conflict (another request under it)."""
        if done.kind != kind or done.request_hash != digest:
            raise StepConflict(
                f"step key '{key}' was already used for a different request ({done.kind}); "
                "send a new key for a new step"
            )
        state = session_state(db, self.ctx.config, sess)
        state["replayed"] = True
        return state

    # ---- the steps' work -------------------------------------------------------------------
    def begin(self, db: Session, sess: SessionRow) -> ShownPopulation:
        """Instructions read: the first trial starts (generation 0 is made and stored)."""
        if sess.stage != "instructions":
            raise StepConflict(f"the session is past the instructions (stage '{sess.stage}')")
        sess.stage = "trial"
        sess.started_at = utcnow()
        return self.engines.start(db, sess, 0)

    def prepare_select(
        self, token: str, *, trial: int, attempt: int, generation: int, elite: int,
        others: list[int],
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
        known = self.engines.latest(token, trial, attempt, generation)  # stored by this process
        if known is not None:
            state, identity = known
        else:
            with self.store.engine.connect() as conn:  # one plain read, no ORM session
                found = conn.execute(
                    _ACTIVE_TRIAL, {"token": token, "study_id": self.ctx.study_id}
                ).first()
            if found is None:
                return None
            state, identity, position, row_attempt, row_generation = found
            if (position, row_attempt, row_generation) != (trial, attempt, generation):
                return None
        if not state:
            return None
        try:
            engine = self.engines.restore_state(state, identity)
            engine.tell(elite, others)
            if engine.done:
                engine.result  # noqa: B018 - corrected here, not under the lock
            else:
                engine.ask()
            next_state = engine.to_json()
        except EmoGenError:
            return None
        return Prepared(state, engine, next_state)

    def select(
        self, conn: Connection, read: StepRead, *, key: str, trial: int, attempt: int,
        generation: int, elite: int, others: list[int], timing: Timing,
        prepared: Prepared | None = None,
    ) -> tuple[ShownPopulation | None, TrialRecord]:  # fmt: skip
        """The participant's selection of the shown generation; the next one is stored
        (``prepared``: the GA's work done beforehand, see :meth:`prepare_select`)."""
        row, pop = self._shown(read, trial, attempt, generation)
        next_state = None
        if prepared is not None and prepared.engine_state == row.engine_state:
            engine = prepared.engine  # computed from this very state, outside the lock
            next_state = prepared.next_state
        else:
            engine = self.engines.restore(row)
            engine.tell(elite, others)
        now = utcnow()
        conn.execute(
            INSERT_SELECTION,
            {
                "population_id": pop.id,
                "trial_id": row.id,
                "elite_face_id": elite,
                "other_face_ids": dumps(list(others)),
                "submitted_at": now,
                "server_response_ms": server_ms(now, pop.shown_at, timing.load_ms),
                "client_response_ms": timing.response_ms,
                "load_ms": timing.load_ms,
                "step_key": key,
            },
        )
        state = next_state if next_state is not None else engine.to_json()
        if engine.done:
            final = int(engine.result.ids[0])
            row = advance_trial(conn, row, status="rating", final_face_id=final,
                                 generation=engine.generation, engine_state=state)  # fmt: skip
            return None, row
        shown = store_population(conn, row, engine.ask())
        row = advance_trial(conn, row, generation=engine.generation, engine_state=state)
        self.engines.keep(state, row.identity, engine)
        return replace(shown, trial=row), row

    def restart(
        self, conn: Connection, read: StepRead, *, key: str, trial: int, attempt: int,
        generation: int, timing: Timing,
    ) -> tuple[ShownPopulation, TrialRecord]:  # fmt: skip
        """'Start again': a new attempt of the trial at generation 0 (reinitialised or kept)."""
        if not self.ctx.config.allow_restart:
            raise StepConflict("this study does not allow starting a trial again")
        row, pop = self._shown(read, trial, attempt, generation)
        engine = self.engines.restore(row)
        now = utcnow()
        conn.execute(
            INSERT_RESTART,
            {
                "population_id": pop.id,
                "trial_id": row.id,
                "submitted_at": now,
                "server_response_ms": server_ms(now, pop.shown_at, timing.load_ms),
                "client_response_ms": timing.response_ms,
                "load_ms": timing.load_ms,
                "step_key": key,
            },
        )
        population = engine.reset()
        shown = store_population(conn, row, population)
        state = engine.to_json()
        row = advance_trial(
            conn, row, attempt=engine.trial, generation=engine.generation, engine_state=state
        )
        self.engines.keep(state, row.identity, engine)
        return replace(shown, trial=row), row

    def rate(
        self, db: Session, sess: SessionRow, *, key: str, trial: int, value: int,
        response_ms: float | None,
    ) -> ShownPopulation | None:  # fmt: skip
        """The rating of the trial's final face; then the next trial starts (or the session ends)."""
        points = self.ctx.config.rating.points
        row = self._current_trial(db, sess, trial)
        if row.status != "rating":
            raise StepConflict(
                f"trial {trial + 1} is not waiting for a rating (it is at generation "
                f"{row.generation}); reload the page"
            )
        if not 1 <= value <= points:
            raise SelectionError(f"rating must be an integer in [1, {points}]; got {value}")
        now = utcnow()
        db.add(
            RatingRow(
                trial_id=row.id,
                face_id=int(row.final_face_id if row.final_face_id is not None else -1),
                value=value,
                points=points,
                submitted_at=now,
                server_response_ms=elapsed_ms(now, last_selection_time(db, row.id)),
                client_response_ms=response_ms,
                step_key=key,
            )
        )
        row.status = "done"
        row.finished_at = now
        if trial + 1 < n_trials(sess):
            sess.current_trial = trial + 1
            return self.engines.start(db, sess, trial + 1)
        sess.stage = "done"
        sess.completed_at = now
        return None

    # ---- guards ----------------------------------------------------------------------------
    @staticmethod
    def _check_trial(sess: SessionRow | SessionRecord, trial: int) -> None:
        if sess.stage != "trial":
            raise StepConflict(
                f"the session is not in a trial (stage '{sess.stage}'); reload the page"
            )
        if trial != sess.current_trial:
            raise StepConflict(
                f"this request is for trial {trial + 1}, but the session is at trial "
                f"{sess.current_trial + 1}; reload the page"
            )

    def _current_trial(self, db: Session, sess: SessionRow, trial: int) -> TrialRow:
        self._check_trial(sess, trial)
        row = trial_at(db, sess.id, trial)
        if row is None:  # pragma: no cover - created with the session
            raise SessionNotFound(f"trial {trial + 1} does not exist")
        return row

    def _shown(
        self, read: StepRead, trial: int, attempt: int, generation: int
    ) -> tuple[TrialRecord, ShownAt]:
        """The trial and population a selection or restart is for, as :func:`step_read` found
        them (a conflict if the request is not for what the session shows now)."""
        self._check_trial(read.session, trial)
        row = read.trial  # the session's current trial: the request's, checked above
        if row is None:  # pragma: no cover - created with the session
            raise SessionNotFound(f"trial {trial + 1} does not exist")
        if row.status != "active":
            raise StepConflict(
                f"trial {trial + 1} has no generation to select from (it is waiting for the "
                "rating); reload the page"
            )
        if (attempt, generation) != (row.attempt, row.generation):
            raise StepConflict(
                f"this request is for generation {generation} (attempt {attempt + 1}) of trial "
                f"{trial + 1}, but generation {row.generation} (attempt {row.attempt + 1}) is "
                "shown now; reload the page"
            )
        pop = read.shown  # the trial's population at its attempt and generation: the request's
        if pop is None:  # pragma: no cover - stored with the engine state
            raise StepConflict("the shown generation was not stored; reload the page")
        return row, pop
