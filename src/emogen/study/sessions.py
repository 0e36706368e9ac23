"""The study service: a study's sessions over a :class:`~emogen.study.storage.Store`.

:class:`StudyService` puts the rooms together: enrolment (a session made at consent), the steps
(:mod:`emogen.study.steps`, idempotent transitions), the queries (:mod:`emogen.study.queries`)
and the participant's view (:mod:`emogen.study.view`, the typed browser state every call
answers with).
"""

from __future__ import annotations

import json
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np

from emogen.model.rig import Rig
from emogen.study.check import check_identities
from emogen.study.config import StudyConfig
from emogen.study.context import StudyContext, accepted_hashes, register_study
from emogen.study.enrolment import PARTICIPANT_ID, checked_participant, create_session
from emogen.study.errors import SessionNotFound
from emogen.study.progress import participant_token
from emogen.study.queries import current_trial, session_by_token, sessions_by_source
from emogen.study.records import StudyInfo, TrialRecord, study_info, trial_record
from emogen.study.steps import SessionSteps, request_hash
from emogen.study.storage import Store
from emogen.study.tasking import prepare, rows_of, task_env
from emogen.study.versions import RunningSessions, check_running_sessions, study_versions
from emogen.study.view import Completion, SessionState, completion, session_state
from emogen.study.weights import (
    Floats,
    StudyCorrectors,
    face_weight_names,
    full_weights,
    weight_names,
)
from emogen.tasks.protocol import Command
from emogen.tasks.registry import parse_command, task_named

if TYPE_CHECKING:
    from emogen.model.face import FaceModel

__all__ = [
    "PARTICIPANT_ID",
    "StudyContext",
    "StudyCorrectors",
    "StudyService",
    "full_weights",
    "request_hash",
    "weight_names",
]


class StudyService:
    """The study's steps over a :class:`Store`. Methods return the participant's state.

    model : the face model, needed when the config corrects faces (``correct = true``): every
    face shown is then corrected, and a face's stored (and shown) weights are the shape weights
    followed by the corrective weights, in the model GLB's morph-target order.
    """

    def __init__(
        self,
        config: StudyConfig,
        store: Store,
        rig: Rig,
        *,
        model_name: str,
        model_hash: str,
        model: FaceModel | None = None,
        running_sessions: RunningSessions = "refuse",
    ) -> None:
        check_identities(config, rig, model)
        self.store = store
        self.correctors = StudyCorrectors(config, model)
        genes = tuple(rig.gene_names(config.ga.eye_motion))
        names = tuple(face_weight_names(config, rig, self.correctors))
        study_id = register_study(
            store,
            config,
            model_name=model_name,
            model_hash=model_hash,
            gene_names=genes,
            weight_names=names,
            aliases=accepted_hashes(model_hash, model),
        )
        versions = study_versions(store, study_id)
        #: unfinished sessions of another design ended at start (``running_sessions="end"``)
        self.ended = check_running_sessions(store, study_id, versions, running_sessions)
        ctx = StudyContext(
            config,
            rig,
            model_name,
            model_hash,
            study_id,
            genes,
            names,
            same_design=versions.same_design,
            all_versions=versions.all_versions,
        )
        prepared = prepare(ctx)  # the blocks' face tables, checked before anyone starts
        self.ctx = replace(ctx, conditions=tuple(config.conditions(rows_of(ctx, prepared))))
        self.env = task_env(self.ctx, self.correctors, prepared)
        self.steps = SessionSteps(self.ctx, store, self.env)

    @property
    def n_trials(self) -> int:
        """Trials per session (every block's; a block's face-table rows counted)."""
        return len(self.ctx.conditions)

    def create_session(
        self,
        participant_id: str | None = None,
        *,
        resume_token: str | None = None,
        create_key: str | None = None,
        user_agent: str = "",
        source: str | None = None,
    ) -> tuple[str, SessionState]:
        """Consent given: a new session (token, state), or the participant's own one again
        (``create_key``: a retried create gets the same session; ``source``: ``simulated``
        for :mod:`emogen.study.simulate`'s participants)."""
        return create_session(
            self.store,
            self.env,
            participant_id,
            resume_token=resume_token,
            create_key=create_key,
            user_agent=user_agent,
            source=source,
        )

    def state(self, token: str) -> SessionState:
        with self.store.read() as db:
            return session_state(db, self.env, session_by_token(db, token, self.ctx.accepted))

    def step(self, token: str, command: Command | dict[str, Any]) -> SessionState:
        """One step of the session: ``begin`` or a command of the current trial's task (a
        command object, or its JSON body: :func:`emogen.tasks.registry.parse_command`)."""
        cmd = command if isinstance(command, Command) else parse_command(command)
        return self.steps.step(token, cmd)

    def study_info(self) -> StudyInfo:
        """The study's blocks and weight names (for a page that embeds the study)."""
        return study_info(self.ctx)

    def trial_record(self, token: str, position: int) -> TrialRecord:
        """Trial ``position`` of the caller's session as recorded: session id, seeds, final face."""
        with self.store.read() as db:
            sess = session_by_token(db, token, self.ctx.accepted)
            return trial_record(db, self.env, sess, position)

    def participant_token(self, participant_id: str) -> str:
        """The token of the participant's session in this study (404 when there is none)."""
        checked_participant(participant_id)  # a bad id is named as such
        return participant_token(self.store, participant_id, study=self.ctx.config.name)

    def participant_sources(self) -> dict[str, int]:
        """Sessions of this study by where their participant id came from (url, generated…)."""
        with self.store.read() as db:
            return sessions_by_source(db, self.ctx.accepted)

    def completion(self, participant_id: str) -> Completion:
        return completion(self.ctx.config, participant_id)

    def face_weights(
        self, token: str, face_id: int, trial: int | None = None, attempt: int | None = None
    ) -> tuple[Floats, str]:
        """(full weights (n_columns,), identity) of a face of the caller's current trial (and,
        where given, only if that is trial position ``trial`` in its attempt ``attempt``); a
        face that moves as its frames' weights (frames, n_shapes) (``Task.face``)."""
        with self.store.read() as db:
            sess = session_by_token(db, token, self.ctx.accepted)
            if sess.stage != "trial":
                raise SessionNotFound("no faces are shown now")
            row = None if trial not in (None, sess.current_trial) else current_trial(db, sess)
            if row is not None and attempt is not None and row.attempt != attempt:
                row = None
            found = None if row is None else task_named(row.task).face(self.env, db, row, face_id)
        if found is None:
            where = "" if trial is None else f" (trial {trial}, attempt {attempt or 0})"
            raise SessionNotFound(f"face {face_id}{where} is not in this session's current trial")
        return np.asarray(json.loads(found[0]), dtype=np.float64), found[1]
