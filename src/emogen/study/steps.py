"""The study's steps: each one transaction, committed before it is answered, and idempotent.

A session goes consent (its creation) → instructions → trial 1 … T → done. Every step is a
command (:class:`~emogen.tasks.protocol.Command`): ``begin`` (the instructions read) is the
study's own; every other command belongs to a task (:mod:`emogen.tasks.registry`) and is
handed to the task of the session's current trial, which stores what it makes; when the task
says the trial is done, the next trial's task starts it (what it shows is stored first) or the
session ends. The task's state is kept with the trial, so a reload or a server restart resumes
exactly where the participant was.

Every step carries an idempotency key: the same key again returns the current state without
doing anything (a double click, a retried request); a key reused for a different request, a
command the current trial's task does not take, or a request for a trial or screen that is no
longer shown, is a conflict (HTTP 409).
"""

from __future__ import annotations

import hashlib
import json
import logging
from collections.abc import Mapping
from typing import Any

from sqlalchemy.orm import Session
from sqlalchemy.orm.attributes import set_committed_value

from emogen.errors import EmoGenError
from emogen.study.context import StudyContext
from emogen.study.errors import SessionNotFound, StepConflict
from emogen.study.queries import n_trials, session_by_token, step_with_key, trial_at
from emogen.study.storage import Store
from emogen.study.tables import SessionRow, TrialRow, utcnow
from emogen.study.view import SessionState, session_state
from emogen.study.writes import record_step
from emogen.tasks.protocol import Command, Outcome, TaskEnv, TrialCommand
from emogen.tasks.registry import command_name, task_named

log = logging.getLogger(__name__)


def request_hash(kind: str, payload: Mapping[str, Any]) -> str:
    text = kind + ":" + json.dumps(payload, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


class SessionSteps:
    """The transitions of a session: one :meth:`step` per command."""

    def __init__(self, ctx: StudyContext, store: Store, env: TaskEnv) -> None:
        self.ctx = ctx
        self.store = store
        self.env = env
        #: some block's trials are worked ahead (:meth:`_ahead`); none: no read is spent on it
        self.works_ahead = any(b.works_ahead for b in ctx.config.study_blocks())

    def step(self, token: str, cmd: Command) -> SessionState:
        """Do ``cmd`` once per key, in one transaction; answer the session's state."""
        digest = request_hash(cmd.command, cmd.payload())
        self._ahead(token, cmd)

        def work(db: Session) -> SessionState:
            sess = session_by_token(db, token, self.ctx.accepted, lock=True)
            done = step_with_key(db, sess.id, cmd.key)
            if done is not None:
                if done.kind != cmd.command or done.request_hash != digest:
                    raise StepConflict(
                        f"step key '{cmd.key}' was already used for a different request "
                        f"({done.kind}); send a new key for a new step"
                    )
                state = session_state(db, self.env, sess)
                state["replayed"] = True
                return state
            shown = self._take(db, sess, cmd)
            db.flush()  # what the step changed
            at = record_step(db, sess.id, cmd.command, cmd.key, digest)
            set_committed_value(sess, "updated_at", at)
            return session_state(db, self.env, sess, shown)

        return self.store.transact(work)

    def _ahead(self, token: str, cmd: Command) -> None:
        """The current trial's task's work ahead of the write transaction (the optional
        ``ahead`` of :mod:`emogen.tasks.protocol`), in a read of the session as it is now. Only
        a hint: whatever it meets (a stale or repeated request, a wrong selection, an error) is
        left to the write transaction, which does the step whole and says so."""
        if not (self.works_ahead and isinstance(cmd, TrialCommand)):
            return
        try:
            with self.store.read() as db:
                sess = session_by_token(db, token, self.ctx.accepted)
                if sess.stage != "trial" or cmd.trial != sess.current_trial:
                    return
                if step_with_key(db, sess.id, cmd.key) is not None:
                    return  # answered already: nothing to make
                row = trial_at(db, sess.id, cmd.trial)
                if row is None or not self.env.block(row).works_ahead:
                    return
                task = task_named(row.task)
                ahead = getattr(task, "ahead", None)
                if ahead is not None and type(cmd) in task.commands:
                    ahead(self.env, db, row, cmd)
        except (EmoGenError, ValueError) as exc:  # the write transaction meets it and says so
            log.debug("step ahead of %s skipped: %s", cmd.command, exc)
        except Exception:  # an error here must not stop the step: the step itself decides
            log.warning("step ahead of %s failed; the step goes on", cmd.command, exc_info=True)

    def _take(self, db: Session, sess: SessionRow, cmd: Command) -> Outcome:
        """The command's work on the locked session: what the step has just shown."""
        if not isinstance(cmd, TrialCommand):  # the study's own: the instructions read
            if sess.stage != "instructions":
                raise StepConflict(f"the session is past the instructions (stage '{sess.stage}')")
            sess.stage = "trial"
            sess.started_at = utcnow()
            return self._start(db, sess, 0)
        row = self._current(db, sess, cmd.trial)
        task = task_named(row.task)
        if type(cmd) not in task.commands:
            names = [command_name(c) for c in task.commands]
            takes = " or ".join([", ".join(names[:-1]), names[-1]] if len(names) > 1 else names)
            article = "an" if row.task[:1] in "aeiou" else "a"
            raise StepConflict(
                f"trial {cmd.trial + 1} is {article} {row.task} trial: it takes {takes}, not "
                f"{cmd.command}; reload the page"
            )
        outcome = task.accept(self.env, db, row, cmd)
        if not outcome.done:
            return outcome
        if cmd.trial + 1 < n_trials(sess):
            sess.current_trial = cmd.trial + 1
            return self._start(db, sess, cmd.trial + 1)
        sess.stage = "done"
        sess.completed_at = utcnow()
        return Outcome(done=True)

    def _start(self, db: Session, sess: SessionRow, position: int) -> Outcome:
        """Start the session's trial at ``position`` by its task: what it shows is stored
        first."""
        row = trial_at(db, sess.id, position)
        if row is None:  # pragma: no cover - created with the session
            raise SessionNotFound(f"trial {position + 1} does not exist")
        return task_named(row.task).start(self.env, db, row, sess.id)

    @staticmethod
    def _current(db: Session, sess: SessionRow, trial: int) -> TrialRow:
        """The session's current trial, if the command is for it (a conflict otherwise)."""
        if sess.stage != "trial":
            raise StepConflict(
                f"the session is not in a trial (stage '{sess.stage}'); reload the page"
            )
        if trial != sess.current_trial:
            raise StepConflict(
                f"this request is for trial {trial + 1}, but the session is at trial "
                f"{sess.current_trial + 1}; reload the page"
            )
        row = trial_at(db, sess.id, trial)
        if row is None:  # pragma: no cover - created with the session
            raise SessionNotFound(f"trial {trial + 1} does not exist")
        return row
