"""The participant's view of a session: the state the browser shows, as typed JSON.

These TypedDicts are the browser contract: the web layer answers with them and its OpenAPI
schema (and the JS types generated from it) are derived from them. A step that has just shown a
population passes it in (:class:`ShownPopulation`) so it is not read back from the database.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal, NotRequired
from urllib.parse import quote

from sqlalchemy.orm import Session
from typing_extensions import TypedDict

from emogen.study.categorise import categorise_state
from emogen.study.config import StudyConfig
from emogen.study.queries import (
    final_face,
    n_trials,
    population_at,
    trial_at,
)
from emogen.study.tables import SessionRow, TrialRow
from emogen.tasks.categorise import CategoriseView
from emogen.tasks.protocol import FaceView

__all__ = ["FaceView", "SessionState", "ShownPopulation", "completion", "session_state"]

Stage = Literal["instructions", "trial", "done"]
TrialStatus = Literal["pending", "active", "rating", "done"]


class Progress(TypedDict):
    """Trial, block and generation shown (0-based) of how many."""

    trial: int
    trials: int
    block: int
    blocks: int
    generation: int
    generations: int


class Limits(TypedDict):
    """How many faces a selection takes (the elite included)."""

    min_selections: int
    max_selections: int


class TrialView(TypedDict):
    """The current trial: its task and block; an evolve trial's emotion on its identity (a
    categorise trial's emotion is "": the participant is not told what the face was made for)."""

    position: int
    block: int
    task: str
    emotion: str
    prompt: str
    identity: str
    attempt: int
    status: TrialStatus


class PopulationView(TypedDict):
    """The generation shown for selection."""

    attempt: int
    generation: int
    faces: list[FaceView]


class RatingView(TypedDict):
    """The rating asked of the trial's final face."""

    question: str
    low_label: str
    high_label: str
    points: int
    face: FaceView | None


class Completion(TypedDict):
    """What a participant sees at the end: a message, a code, a link back."""

    message: str
    code: str | None
    redirect_url: str | None


class SessionState(TypedDict):
    """The participant's view of the session."""

    stage: Stage
    participant_id: str
    progress: Progress
    limits: Limits
    allow_restart: bool
    trial: TrialView | None
    population: PopulationView | None
    rating: RatingView | None
    #: a categorise trial's face and labels
    categorise: CategoriseView | None
    completion: Completion | None
    #: true when the request's step key was already done (nothing was changed)
    replayed: NotRequired[bool]


@dataclass(frozen=True)
class ShownPopulation:
    """A population a step has just stored and shows, keyed by where it belongs."""

    trial_id: int
    attempt: int
    generation: int
    faces: list[FaceView]
    #: the trial's row, as the step left it (the view then reads it without a query)
    trial: TrialRow | None = field(default=None, compare=False)


def completion(config: StudyConfig, participant_id: str) -> Completion:
    """The end of the study, with the participant's code and redirect link filled in."""
    c = config.completion
    url = None
    if c.redirect_url:
        code, pid = quote(c.code or "", safe=""), quote(participant_id, safe="")
        url = c.redirect_url
        for name in ("code", "completion_code"):
            url = url.replace("{" + name + "}", code)
        for name in ("participant", "participant_id", config.participant_param):
            url = url.replace("{" + name + "}", pid)
    return {"message": c.message, "code": c.code, "redirect_url": url}


def _face(face_id: int, weights_json: str) -> FaceView:
    return {"id": face_id, "weights": json.loads(weights_json)}


def _population(db: Session, row: TrialRow, shown: ShownPopulation | None) -> PopulationView | None:
    if shown is not None and (shown.trial_id, shown.attempt, shown.generation) == (
        row.id,
        row.attempt,
        row.generation,
    ):
        return {"attempt": shown.attempt, "generation": shown.generation, "faces": shown.faces}
    pop = population_at(db, row.id, row.attempt, row.generation, with_faces=True)
    if pop is None:
        return None
    faces = [_face(f.face_id, f.weights) for f in pop.faces]
    return {"attempt": pop.attempt, "generation": pop.generation, "faces": faces}


def _rating(db: Session, config: StudyConfig, row: TrialRow) -> RatingView:
    face = final_face(db, row)
    r = config.rating
    return {
        "question": r.question,
        "low_label": r.low_label,
        "high_label": r.high_label,
        "points": r.points,
        "face": None if face is None else _face(face.face_id, face.weights),
    }


def _current_trial(db: Session, sess: SessionRow, shown: ShownPopulation | None) -> TrialRow | None:
    """The session's current trial: the one a step has just shown a population of (no query),
    or the one read."""
    row = None if shown is None else shown.trial
    if row is not None and row.session_id == sess.id and row.position == sess.current_trial:
        return row
    return trial_at(db, sess.id, sess.current_trial)


def session_state(
    db: Session,
    config: StudyConfig,
    sess: SessionRow,
    shown: ShownPopulation | None = None,
) -> SessionState:
    """The session as the participant sees it now (``shown``: a population a step has just
    stored, with its trial's row)."""
    trials = n_trials(sess)
    generations = config.ga.generations
    blocks = len(config.study_blocks())
    stage: Stage = (
        "done" if sess.stage == "done" else "trial" if sess.stage == "trial" else "instructions"
    )
    state: SessionState = {
        "stage": stage,
        "participant_id": sess.participant_id,
        "progress": {
            "trial": sess.current_trial,
            "trials": trials,
            "block": 0,
            "blocks": blocks,
            "generation": 0,
            "generations": generations,
        },
        "limits": {
            "min_selections": config.ga.min_selections,
            "max_selections": config.ga.max_selections,
        },
        "allow_restart": config.allow_restart,
        "trial": None,
        "population": None,
        "rating": None,
        "categorise": None,
        "completion": None,
    }
    if stage == "done":
        state["completion"] = completion(config, sess.participant_id)
        state["progress"]["trial"] = trials - 1
        state["progress"]["generation"] = generations
        state["progress"]["block"] = blocks - 1
        return state
    row = _current_trial(db, sess, shown) if stage == "trial" else None
    if row is None:
        return state
    status: TrialStatus = row.status  # type: ignore[assignment]  # a stored TrialStatus
    state["progress"]["block"] = row.block
    state["trial"] = {
        "position": row.position,
        "block": row.block,
        "task": row.task,
        "emotion": "",
        "prompt": "",
        "identity": row.identity,
        "attempt": row.attempt,
        "status": status,
    }
    state["progress"]["generation"] = row.generation
    TRIAL_VIEWS[row.task](db, config, row, shown, state)
    return state


# ---- each task's part of the state (a task adds its function here) ------------------------
def _evolve_view(
    db: Session, config: StudyConfig, row: TrialRow, shown: ShownPopulation | None,
    state: SessionState,
) -> None:  # fmt: skip
    """An evolve trial: its emotion and prompt, the generation shown or the rating asked."""
    trial = state["trial"]
    if trial is not None:
        trial["emotion"], trial["prompt"] = row.emotion, config.prompt_for(row.emotion)
    if row.status == "active":
        state["population"] = _population(db, row, shown)
    elif row.status == "rating":
        state["rating"] = _rating(db, config, row)


def _categorise_view(
    db: Session, config: StudyConfig, row: TrialRow, shown: ShownPopulation | None,
    state: SessionState,
) -> None:  # fmt: skip
    """A categorise trial: its face and labels (the participant is not told the emotion the
    face was made for); its question is the prompt."""
    view = categorise_state(db, config, row)
    state["categorise"] = view
    if view is not None and state["trial"] is not None:
        state["trial"]["prompt"] = view["question"]


#: The participant's view of a trial, by task (:data:`emogen.tasks.protocol.TASKS`).
TRIAL_VIEWS: dict[
    str, Callable[[Session, StudyConfig, TrialRow, ShownPopulation | None, SessionState], None]
] = {"evolve": _evolve_view, "categorise": _categorise_view}
