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
from dataclasses import replace

from sqlalchemy.orm import Session
from sqlalchemy.orm.attributes import set_committed_value

from emogen.errors import SelectionError
from emogen.study.categorise import CategoriseTrials
from emogen.study.context import StudyContext
from emogen.study.errors import SessionNotFound, StepConflict
from emogen.study.queries import (
    StepTaken,
    last_selection_time,
    n_trials,
    population_at,
    session_by_token,
    step_with_key,
    trial_at,
)
from emogen.study.storage import Store
from emogen.study.tables import (
    PopulationRow,
    RatingRow,
    RestartRow,
    SelectionRow,
    SessionRow,
    TrialRow,
    dumps,
    utcnow,
)
from emogen.study.trials import TrialEngines, store_population
from emogen.study.view import SessionState, ShownPopulation, session_state
from emogen.study.writes import Timing, elapsed_ms, record_step, server_ms
from emogen.tasks.protocol import TaskRunner

#: What a step's request held (hashed to tell a replayed key from a reused one).
Payload = Mapping[str, int | float | str | list[int] | None]
#: A step's work on the locked session; returns the population it has just shown, if any.
Action = Callable[[Session, SessionRow], ShownPopulation | None]


def request_hash(kind: str, payload: Payload) -> str:
    text = kind + ":" + json.dumps(payload, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


class SessionSteps:
    """The transitions of a session: begin, select, restart, rate (each under a step key)."""

    def __init__(
        self, ctx: StudyContext, store: Store, engines: TrialEngines, categorise: CategoriseTrials
    ) -> None:
        self.ctx = ctx
        self.store = store
        self.engines = engines
        self.categorise_trials = categorise
        #: each task's runner: what starts its trials (a task adds its runner here)
        self.runners: dict[str, TaskRunner] = {r.task: r for r in (engines, categorise)}

    def run(
        self, token: str, kind: str, key: str, payload: Payload, action: Action
    ) -> SessionState:
        """Do ``action`` once per key, in one transaction; answer the session's state."""
        digest = request_hash(kind, payload)

        def work(db: Session) -> SessionState:
            sess = session_by_token(db, token, self.ctx.accepted, lock=True)
            replayed = self._replayed(db, sess, kind, key, digest)
            if replayed is not None:
                return replayed
            shown = action(db, sess)
            db.flush()  # what the step changed
            set_committed_value(sess, "updated_at", record_step(db, sess.id, kind, key, digest))
            return session_state(db, self.ctx.config, sess, shown)

        return self.store.transact(work)

    def _replayed(
        self, db: Session, sess: SessionRow, kind: str, key: str, digest: str
    ) -> SessionState | None:
        """The current state if this key's step was already taken (a conflict if the key was
        used for another request); None for a new step."""
        done = step_with_key(db, sess.id, key)
        return None if done is None else self._replay(db, sess, done, kind, key, digest)

    def _replay(
        self, db: Session, sess: SessionRow, done: StepTaken, kind: str, key: str, digest: str
    ) -> SessionState:
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
    def begin(self, db: Session, sess: SessionRow) -> ShownPopulation | None:
        """Instructions read: the first trial starts (generation 0 is made and stored)."""
        if sess.stage != "instructions":
            raise StepConflict(f"the session is past the instructions (stage '{sess.stage}')")
        sess.stage = "trial"
        sess.started_at = utcnow()
        return self.start_trial(db, sess, 0)

    def start_trial(self, db: Session, sess: SessionRow, position: int) -> ShownPopulation | None:
        """Start the session's trial at ``position`` by its task: what it shows is stored first
        (an evolve trial's generation 0; a categorise trial's face, its block's drawn at once)."""
        row = trial_at(db, sess.id, position)
        if row is None:  # pragma: no cover - created with the session
            raise SessionNotFound(f"trial {position + 1} does not exist")
        return self.runners[row.task].start(db, sess, row)  # type: ignore[no-any-return]

    def next_trial(self, db: Session, sess: SessionRow, trial: int) -> ShownPopulation | None:
        """The trial at ``trial`` is finished: the next one starts, or the session ends."""
        if trial + 1 < n_trials(sess):
            sess.current_trial = trial + 1
            return self.start_trial(db, sess, trial + 1)
        sess.stage = "done"
        sess.completed_at = utcnow()
        return None

    def select(
        self, db: Session, sess: SessionRow, *, key: str, trial: int, attempt: int,
        generation: int, elite: int, others: list[int], timing: Timing,
    ) -> ShownPopulation | None:  # fmt: skip
        """The participant's selection of the shown generation; the next one is stored (or
        the trial waits for its rating)."""
        row, pop = self._shown(db, sess, trial, attempt, generation)
        engine = self.engines.restore(row)
        engine.tell(elite, others)
        now = utcnow()
        db.add(
            SelectionRow(
                population_id=pop.id,
                trial_id=row.id,
                elite_face_id=elite,
                other_face_ids=dumps(list(others)),
                submitted_at=now,
                server_response_ms=server_ms(now, pop.shown_at, timing.load_ms),
                client_response_ms=timing.response_ms,
                load_ms=timing.load_ms,
                step_key=key,
            )
        )
        row.generation = engine.generation
        row.engine_state = engine.to_json()
        if engine.done:
            row.status = "rating"
            row.final_face_id = int(engine.result.ids[0])
            return None
        return replace(store_population(db, row, engine.ask()), trial=row)

    def restart(
        self, db: Session, sess: SessionRow, *, key: str, trial: int, attempt: int,
        generation: int, timing: Timing,
    ) -> ShownPopulation:  # fmt: skip
        """'Start again': a new attempt of the trial at generation 0 (reinitialised or kept)."""
        if not self.ctx.config.allow_restart:
            raise StepConflict("this study does not allow starting a trial again")
        row, pop = self._shown(db, sess, trial, attempt, generation)
        engine = self.engines.restore(row)
        now = utcnow()
        db.add(
            RestartRow(
                population_id=pop.id,
                trial_id=row.id,
                submitted_at=now,
                server_response_ms=server_ms(now, pop.shown_at, timing.load_ms),
                client_response_ms=timing.response_ms,
                load_ms=timing.load_ms,
                step_key=key,
            )
        )
        shown = store_population(db, row, engine.reset())
        row.attempt = engine.attempt
        row.generation = engine.generation
        row.engine_state = engine.to_json()
        return replace(shown, trial=row)

    def rate(
        self, db: Session, sess: SessionRow, *, key: str, trial: int, value: int,
        response_ms: float | None,
    ) -> ShownPopulation | None:  # fmt: skip
        """The rating of the trial's final face; then the next trial starts (or the session ends)."""
        points = self.ctx.config.rating.points
        row = self._current_trial(db, sess, trial, "evolve")
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
        return self.next_trial(db, sess, trial)

    def categorise(
        self, db: Session, sess: SessionRow, *, key: str, trial: int, label: str,
        intensity: int | None, confidence: int | None, timing: Timing,
    ) -> ShownPopulation | None:  # fmt: skip
        """The participant's label (and ratings) of a categorise trial's face; then the next
        trial starts (or the session ends)."""
        row = self._current_trial(db, sess, trial, "categorise")
        if row.status != "active":  # pragma: no cover - a done trial is no longer current
            raise StepConflict(f"trial {trial + 1} is not waiting for an answer; reload the page")
        self.categorise_trials.respond(db, row, key=key, label=label, intensity=intensity,
                                       confidence=confidence, timing=timing)  # fmt: skip
        return self.next_trial(db, sess, trial)

    # ---- guards ----------------------------------------------------------------------------
    @staticmethod
    def _check_trial(sess: SessionRow, trial: int) -> None:
        if sess.stage != "trial":
            raise StepConflict(
                f"the session is not in a trial (stage '{sess.stage}'); reload the page"
            )
        if trial != sess.current_trial:
            raise StepConflict(
                f"this request is for trial {trial + 1}, but the session is at trial "
                f"{sess.current_trial + 1}; reload the page"
            )

    def _current_trial(self, db: Session, sess: SessionRow, trial: int, task: str) -> TrialRow:
        self._check_trial(sess, trial)
        row = trial_at(db, sess.id, trial)
        if row is None:  # pragma: no cover - created with the session
            raise SessionNotFound(f"trial {trial + 1} does not exist")
        _check_task(row, trial, task)
        return row

    def _shown(
        self, db: Session, sess: SessionRow, trial: int, attempt: int, generation: int
    ) -> tuple[TrialRow, PopulationRow]:
        """The trial and population a selection or restart is for (a conflict if the request is
        not for what the session shows now)."""
        row = self._current_trial(db, sess, trial, "evolve")
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
        pop = population_at(db, row.id, row.attempt, row.generation)
        if pop is None:  # pragma: no cover - stored with the engine state
            raise StepConflict("the shown generation was not stored; reload the page")
        return row, pop


_WHAT = {"evolve": "makes a face (selections)", "categorise": "asks for a label"}


def _check_task(row: TrialRow, trial: int, task: str) -> None:
    """A step of ``task`` must be for a trial of that task."""
    if row.task != task:
        article = "an" if row.task[:1] in "aeiou" else "a"
        raise StepConflict(
            f"trial {trial + 1} is {article} {row.task} trial: it "
            f"{_WHAT.get(row.task, 'is another task')}, not a {task} step; reload the page"
        )
