"""What a participant is shown of an evolve trial: the emotion to make, the generation shown
(its faces and the selection's limits) or the rating asked of the final face."""

from __future__ import annotations

import json
from typing import Any, Literal

import numpy as np
from sqlalchemy import select
from sqlalchemy.orm import Session
from typing_extensions import TypedDict

from emogen.ga.genome import DynamicGenome
from emogen.ga.motion import core_at, shape_curves, strip_times
from emogen.tasks.blocks import fill_emotion
from emogen.tasks.evolve.store import ShownPopulation, final_face, population_at
from emogen.tasks.evolve.tables import FaceCurveRow, FaceRow
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


def _moving(
    env: TaskEnv, db: Session, row: TrialRow, population_id: int, faces: list[FaceView], at: int
) -> list[FaceView]:
    """Faces of a dynamic block with their ``motion`` (its stored curves: the faces' timing and
    keyframe correctives), the page's clip of each; ``at``: the first face's position."""
    if not isinstance(env.block(row).genome(), DynamicGenome):
        return faces
    stored = db.scalars(
        select(FaceCurveRow).where(FaceCurveRow.population_id == population_id)
    ).all()
    by_position = {c.position: c for c in stored}
    curves = []
    for k in range(len(faces)):
        curve = by_position[at + k]
        keyed = json.loads(curve.keyframe_correctives)
        curves.append(
            (np.asarray(json.loads(curve.timing)), None if keyed is None else np.asarray(keyed))
        )
    return _with_motion(env, row, faces, curves)


def _with_motion(
    env: TaskEnv,
    row: TrialRow,
    faces: list[FaceView],
    curves: list[tuple[np.ndarray, np.ndarray | None]],
) -> list[FaceView]:
    """Faces of a dynamic block with their ``motion`` from their curves (timing (K, 5) and
    keyframe correctives (F, C) or None, as stored)."""
    genome = env.block(row).genome()
    if not isinstance(genome, DynamicGenome):
        return faces
    expansion = env.ctx.rig.expansion_matrix(env.config.ga_for(row.identity).eye_motion)
    out: list[FaceView] = []
    for face, (timing, keyed) in zip(faces, curves, strict=True):
        motion = {
            "clip_s": genome.clip_s,
            "hold_s": genome.hold_s,
            "curves": shape_curves(genome, timing, expansion).tolist(),
            "keyframes": [] if keyed is None else keyed.tolist(),
        }
        out.append({**face, "motion": motion})  # type: ignore[typeddict-item]
    return out


def face_strip(env: TaskEnv, db: Session, row: TrialRow, face: FaceRow) -> str | None:
    """A face that moves as the server's images show it (browsers without WebGL): JSON of its
    core weights at :func:`emogen.ga.motion.strip_times`, one row a frame (the image is the
    strip of those frames, each corrected on its own); None for a still face."""
    genome = env.block(row).genome()
    if not isinstance(genome, DynamicGenome):
        return None
    curve = db.scalar(
        select(FaceCurveRow).where(
            FaceCurveRow.population_id == face.population_id,
            FaceCurveRow.position == face.position,
        )
    )
    if curve is None:
        return None
    amplitudes = np.asarray(json.loads(face.genes))[:, None]
    genes = np.concatenate([amplitudes, np.asarray(json.loads(curve.timing))], axis=1)
    eye_motion = env.config.ga_for(row.identity).eye_motion
    expand = lambda g: env.ctx.rig.expand(g, eye_motion)  # noqa: E731
    frames = core_at(genome, genes[None], strip_times(genome), expand)[0]
    return json.dumps(frames.tolist())


def _population(env: TaskEnv, db: Session, row: TrialRow, shown: Any) -> PopulationView | None:
    if isinstance(shown, ShownPopulation) and (shown.trial_id, shown.attempt, shown.generation) == (
        row.id,
        row.attempt,
        row.generation,
    ):
        faces = shown.faces
        if shown.curves is not None:  # the step's own population: nothing to read back
            faces = _with_motion(env, row, faces, shown.curves)
    else:
        pop = population_at(db, row.id, row.attempt, row.generation, with_faces=True)
        if pop is None:
            return None
        faces = _moving(env, db, row, pop.id, [_face(f.face_id, f.weights) for f in pop.faces], 0)
    return {"attempt": row.attempt, "generation": row.generation, "faces": faces}


def _rating(env: TaskEnv, db: Session, row: TrialRow) -> RatingView:
    face = final_face(db, row)
    r = env.config.rating
    shown = None
    if face is not None:
        shown = _moving(env, db, row, face.population_id, [_face(face.face_id, face.weights)],
                        face.position)[0]  # fmt: skip
    return {
        "question": fill_emotion(r.question, row.emotion),
        "low_label": r.low_label,
        "high_label": r.high_label,
        "points": r.points,
        "face": shown,
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
        view["population"] = _population(env, db, row, shown)
    elif row.status == "rating":
        view["rating"] = _rating(env, db, row)
    return view
