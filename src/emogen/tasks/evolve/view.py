"""What a participant is shown of an evolve trial: the emotion to make, the generation shown
(its faces and the selection's limits) or the rating asked of the final face."""

from __future__ import annotations

import json
from typing import Any, Literal

from sqlalchemy.orm import Session
from typing_extensions import TypedDict

from emogen.tasks.blocks import fill_emotion
from emogen.tasks.evolve.store import ShownPopulation, final_face, population_at
from emogen.tasks.protocol import FaceView, TaskEnv
from emogen.tasks.records import TrialRow


class Limits(TypedDict):
    """How many faces a selection takes (the elite included)."""

    min_selections: int
    max_selections: int


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


class EvolveView(TypedDict):
    """An evolve trial as the participant sees it: the emotion to make, the generation shown
    (0-based) of how many, the selection's limits, whether "start again" is offered, and the
    generation to select from (while the trial is active) or the rating asked (after its last
    generation)."""

    task: Literal["evolve"]
    emotion: str
    generation: int
    generations: int
    limits: Limits
    allow_restart: bool
    population: PopulationView | None
    rating: RatingView | None


class EvolveResult(TypedDict):
    """An evolve trial's record for an embedding page: the emotion made and, once the trial is
    done, its final face."""

    task: Literal["evolve"]
    emotion: str
    final_face: FaceView | None


def _face(face_id: int, weights_json: str) -> FaceView:
    return {"id": face_id, "weights": json.loads(weights_json)}


def _population(db: Session, row: TrialRow, shown: Any) -> PopulationView | None:
    if isinstance(shown, ShownPopulation) and (shown.trial_id, shown.attempt, shown.generation) == (
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


def _rating(db: Session, config: Any, row: TrialRow) -> RatingView:
    face = final_face(db, row)
    r = config.rating
    return {
        "question": fill_emotion(r.question, row.emotion),
        "low_label": r.low_label,
        "high_label": r.high_label,
        "points": r.points,
        "face": None if face is None else _face(face.face_id, face.weights),
    }


def evolve_view(env: TaskEnv, db: Session, row: TrialRow, shown: Any) -> EvolveView:
    config = env.config
    view: EvolveView = {
        "task": "evolve",
        "emotion": row.emotion,
        "generation": row.generation,
        "generations": config.ga.generations,
        "limits": {
            "min_selections": config.ga.min_selections,
            "max_selections": config.ga.max_selections,
        },
        "allow_restart": config.allow_restart,
        "population": None,
        "rating": None,
    }
    if row.status == "active":
        view["population"] = _population(db, row, shown)
    elif row.status == "rating":
        view["rating"] = _rating(db, config, row)
    return view
