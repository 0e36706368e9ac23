"""The study service: a study's sessions over a :class:`~emogen.study.storage.Store`.

:class:`StudyService` puts the rooms together: enrolment (a session made at consent), the steps
(:mod:`emogen.study.steps`, idempotent transitions), the queries (:mod:`emogen.study.queries`)
and the participant's view (:mod:`emogen.study.view`, the typed browser state every call
answers with).
"""

from __future__ import annotations

import json
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from emogen.ga.engine import Engine
from emogen.model.rig import Rig
from emogen.study.categorise import FACE_ID, CategoriseTrials, block_files, file_rows
from emogen.study.check import check_identities
from emogen.study.config import StudyConfig
from emogen.study.context import StudyContext, accepted_hashes, register_study
from emogen.study.enrolment import PARTICIPANT_ID, checked_participant, create_session
from emogen.study.errors import SessionNotFound
from emogen.study.progress import participant_token
from emogen.study.queries import current_face, session_by_token, sessions_by_source
from emogen.study.records import StudyInfo, TrialRecord, study_info, trial_record
from emogen.study.steps import Payload, SessionSteps, request_hash
from emogen.study.storage import Store
from emogen.study.trials import TrialEngines
from emogen.study.versions import RunningSessions, check_running_sessions, study_versions
from emogen.study.view import Completion, SessionState, completion, session_state
from emogen.study.weights import Floats, StudyCorrectors, full_weights, weight_names
from emogen.study.writes import Timing

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


def _load(load_ms: float | None) -> dict[str, float]:
    """``load_ms`` in a step's request hash only when given (keys recorded before it match)."""
    return {} if load_ms is None else {"load_ms": load_ms}


class StudyService:
    """The study's steps over a :class:`Store`. Methods return the participant's state.

    model : the face model, needed when the config corrects faces (``correct = true``): every
    engine then corrects its populations, and a face's stored (and shown) weights are the shape
    weights followed by the corrective weights, in the model GLB's morph-target order.
    """

    def __init__(self, config: StudyConfig, store: Store, rig: Rig, *, model_name: str,
                 model_hash: str, model: FaceModel | None = None,
                 running_sessions: RunningSessions = "refuse") -> None:  # fmt: skip
        check_identities(config, rig, model)
        self.store = store
        self.correctors = StudyCorrectors(config, model)
        probe = Engine(config.ga_for("generic"), rig, 0, corrector=self.correctors("generic")).ask()
        genes = tuple(rig.gene_names(config.ga.eye_motion))
        names = tuple(weight_names(probe, rig))
        study_id = register_study(store, config, model_name=model_name, model_hash=model_hash,
                                  gene_names=genes, weight_names=names,
                                  aliases=accepted_hashes(model_hash, model))  # fmt: skip
        versions = study_versions(store, study_id)
        #: unfinished sessions of another design ended at start (``running_sessions="end"``)
        self.ended = check_running_sessions(store, study_id, versions, running_sessions)
        ctx = StudyContext(config, rig, model_name, model_hash, study_id, genes, names,
                           same_design=versions.same_design,
                           all_versions=versions.all_versions)  # fmt: skip
        files = block_files(ctx)  # categorise blocks' face tables, checked before anyone starts
        self.ctx = replace(ctx, conditions=tuple(config.conditions(file_rows(files))))
        categorise = CategoriseTrials(self.ctx, self.correctors, files)
        engines = TrialEngines(self.ctx, self.correctors)
        self.steps = SessionSteps(self.ctx, store, engines, categorise)

    @property
    def n_trials(self) -> int:
        """Trials per session (every block's; a categorise block's file rows counted)."""
        return len(self.ctx.conditions)

    def create_session(
        self, participant_id: str | None = None, *, resume_token: str | None = None,
        create_key: str | None = None, user_agent: str = "", source: str | None = None,
    ) -> tuple[str, SessionState]:  # fmt: skip
        """Consent given: a new session (token, state), or the participant's own one again
        (``create_key``: a retried create gets the same session; ``source``: ``simulated``
        for :mod:`emogen.study.simulate`'s participants)."""
        return create_session(self.store, self.ctx, participant_id, resume_token=resume_token,
                              create_key=create_key, user_agent=user_agent,
                              source=source)  # fmt: skip

    def state(self, token: str) -> SessionState:
        with self.store.read() as db:
            return session_state(
                db, self.ctx.config, session_by_token(db, token, self.ctx.accepted)
            )

    def begin(self, token: str, key: str) -> SessionState:
        """Instructions read: the first trial starts (generation 0 is made and stored)."""
        return self.steps.run(token, "begin", key, {}, self.steps.begin)

    def select(
        self, token: str, key: str, *, trial: int, attempt: int, generation: int, elite: int,
        others: list[int], response_ms: float | None = None, load_ms: float | None = None,
    ) -> SessionState:  # fmt: skip
        """The participant's selection of the shown generation; the next one is stored.
        ``load_ms``: the page's time to load and draw the faces (model, textures), if it says."""
        payload: Payload = {"trial": trial, "attempt": attempt, "generation": generation, "elite": elite,
                   "others": others, "response_ms": response_ms, **_load(load_ms)}  # fmt: skip
        return self.steps.run(
            token, "select", key, payload,
            lambda db, sess: self.steps.select(db, sess, key=key, trial=trial, attempt=attempt,
                generation=generation, elite=elite, others=others,
                timing=Timing(response_ms, load_ms)),
        )  # fmt: skip

    def restart(
        self, token: str, key: str, *, trial: int, attempt: int, generation: int,
        response_ms: float | None = None, load_ms: float | None = None,
    ) -> SessionState:  # fmt: skip
        """'Start again': a new attempt of the trial at generation 0 (reinitialised or kept)."""
        payload = {"trial": trial, "attempt": attempt, "generation": generation,
                   "response_ms": response_ms, **_load(load_ms)}  # fmt: skip
        return self.steps.run(
            token, "restart", key, payload,
            lambda db, sess: self.steps.restart(db, sess, key=key, trial=trial, attempt=attempt,
                generation=generation, timing=Timing(response_ms, load_ms)),
        )  # fmt: skip

    def rate(
        self, token: str, key: str, *, trial: int, value: int, response_ms: float | None = None
    ) -> SessionState:
        """The rating of the trial's final face; then the next trial starts (or the session ends)."""
        payload = {"trial": trial, "value": value, "response_ms": response_ms}
        return self.steps.run(
            token, "rate", key, payload,
            lambda db, sess: self.steps.rate(db, sess, key=key, trial=trial, value=value,
                                             response_ms=response_ms),
        )  # fmt: skip

    def categorise(
        self, token: str, key: str, *, trial: int, label: str, intensity: int | None = None,
        confidence: int | None = None, response_ms: float | None = None,
        load_ms: float | None = None,
    ) -> SessionState:  # fmt: skip
        """The participant's label (and ratings, if the block asks) of a categorise trial's
        face; then the next trial starts (or the session ends)."""
        payload: Payload = {"trial": trial, "label": label, "intensity": intensity,
                            "confidence": confidence, "response_ms": response_ms,
                            **_load(load_ms)}  # fmt: skip
        return self.steps.run(
            token, "categorise", key, payload,
            lambda db, sess: self.steps.categorise(db, sess, key=key, trial=trial, label=label,
                intensity=intensity, confidence=confidence,
                timing=Timing(response_ms, load_ms)),
        )  # fmt: skip

    def study_info(self) -> StudyInfo:
        """The study's blocks and weight names (for a page that embeds the study)."""
        return study_info(self.ctx)

    def trial_record(self, token: str, position: int) -> TrialRecord:
        """Trial ``position`` of the caller's session as recorded: session id, seeds, final face."""
        with self.store.read() as db:
            sess = session_by_token(db, token, self.ctx.accepted)
            return trial_record(db, self.ctx, sess, position)

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
        where given, only if that is trial position ``trial`` in its attempt ``attempt``)."""
        with self.store.read() as db:
            sess = session_by_token(db, token, self.ctx.accepted)
            if sess.stage != "trial":
                raise SessionNotFound("no faces are shown now")
            found = current_face(
                db, sess, face_id, categorise_face=FACE_ID, trial=trial, attempt=attempt
            )
        if found is None:
            where = "" if trial is None else f" (trial {trial}, attempt {attempt or 0})"
            raise SessionNotFound(f"face {face_id}{where} is not in this session's current trial")
        return np.asarray(json.loads(found[0]), dtype=np.float64), found[1]
