"""The ``evolve`` task: the paper's GA (Algorithm 1, :class:`emogen.ga.engine.Engine`) over the
trial's generations, then the rating of the final face.

A trial starts with its generation 0 made and stored; each selection is stored and the next
generation made and stored (or, after the last, the trial waits for its rating); "start again"
stores the restart and a new attempt's generation 0; the rating ends the trial. The engine's
JSON state is kept with the trial, so a reload or a server restart resumes exactly where the
participant was. Commands: :class:`Select`, :class:`Restart`, :class:`Rate`.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import replace
from typing import Annotated, Any, ClassVar, Literal

import numpy as np
from pydantic import Field
from sqlalchemy.orm import Session

from emogen.errors import SelectionError
from emogen.ga.corrector import corrected_ahead
from emogen.ga.state import collision_solver_of_state, stream_of_state
from emogen.tasks.blocks import Condition, TaskBlock
from emogen.tasks.errors import StepConflict
from emogen.tasks.evolve import replay_export
from emogen.tasks.evolve.block import EvolveBlock
from emogen.tasks.evolve.export import EVOLVE_TABLES
from emogen.tasks.evolve.replay import replay_trial
from emogen.tasks.evolve.store import (
    faces_per_session,
    final_face,
    final_faces,
    last_selection_time,
    new_engine,
    population_at,
    restore,
    shown_face,
    store_population,
)
from emogen.tasks.evolve.tables import (
    FaceCurveRow,
    FaceRow,
    PopulationRow,
    RatingRow,
    RestartRow,
    SelectionRow,
)
from emogen.tasks.evolve.view import EvolveResult, EvolveView, evolve_view, face_strip
from emogen.tasks.protocol import (
    ExportedStudy,
    FaceId,
    Index,
    MadeFace,
    Millis,
    Outcome,
    Points,
    Replayed,
    TaskEnv,
    TrialCommand,
)
from emogen.tasks.records import TrialRow, dumps, elapsed_ms, server_ms, utcnow


class _Seen(TrialCommand):
    """A command about faces the page showed, and how it showed them."""

    #: The page showed the server's images (no WebGL: a still face as a picture, a moving one
    #: as the strip of its frames played a frame at a time) rather than the 3D viewer; None
    #: when the page did not say (records made before it was sent).
    fallback: bool | None = None


class _Shown(_Seen):
    """A command about the generation shown: its attempt and generation (a stale page's are
    refused), and the page's time to draw it (``load_ms``)."""

    attempt: Index
    generation: Index
    #: Page's time from receiving this population to all its faces drawn (the first faces a
    #: freshly opened page shows: from the page's start, so page, model and textures); the
    #: server's ``server_response_ms`` excludes it.
    load_ms: Millis | None = None


class Select(_Shown):
    """The best face (elite) and the other acceptable faces of the shown generation."""

    command: Literal["select"]
    elite: FaceId
    others: Annotated[list[FaceId], Field(default_factory=list, max_length=100)]


class Restart(_Shown):
    """Start the current trial again at generation 0."""

    command: Literal["restart"]


class Rate(_Seen):
    """The satisfaction rating (1 … points) of the trial's final face."""

    command: Literal["rate"]
    value: Points


class EvolveTask:
    """The GA: selections over generations, then a rating."""

    name: ClassVar[str] = "evolve"
    block: ClassVar[type[TaskBlock]] = EvolveBlock
    commands: ClassVar[tuple[type[TrialCommand], ...]] = (Select, Restart, Rate)
    view_type: ClassVar[type] = EvolveView
    result_type: ClassVar[type] = EvolveResult
    tables: ClassVar[tuple[type, ...]] = (
        PopulationRow,
        FaceRow,
        FaceCurveRow,
        SelectionRow,
        RestartRow,
        RatingRow,
    )
    #: faces, selections, restarts, evolve_ratings, final_faces (:mod:`.export`)
    export_tables: ClassVar[tuple[Any, ...]] = EVOLVE_TABLES
    replay_tables: ClassVar[tuple[str, ...]] = replay_export.TABLES
    #: the default instructions of its blocks
    instructions: ClassVar[str] = (
        "You will see ten faces at a time. Click the face that best shows the emotion you are "
        "asked for: it is marked with a star (★). Then click any other faces that are also "
        "acceptable: they are marked with a tick (✓); the ★ on a face makes that face the best. "
        "Press “Next round” and new faces will be bred from the ones you chose. After the last "
        "round you rate the final face.\n\nKeyboard: Tab or the arrow keys move between faces, "
        "Enter or Space selects, B makes a face the best one."
    )
    #: seconds a screen takes (low, high): :mod:`emogen.study.length`'s sources
    screens: ClassVar[dict[str, tuple[float, float]]] = {
        "selection": (6.0, 9.0),
        "rating": (3.0, 5.0),
    }

    def screens_of(self, condition: Condition, generations: int) -> dict[str, int]:
        """Generations 0 … G are shown, then the rating."""
        return {"selection": generations + 1, "rating": 1}

    def prepare(self, ctx: Any, k: int, block: EvolveBlock) -> None:
        return None

    def rows(self, prepared: None) -> int | None:
        return None

    def start(self, env: TaskEnv, db: Session, row: TrialRow, session_id: int) -> Outcome:
        """Generation 0 is made and stored."""
        engine = new_engine(env, row)
        row.status = "active"
        row.started_at = utcnow()
        row.attempt = engine.attempt
        row.generation = engine.generation
        shown = store_population(db, row, engine.ask())
        row.engine_state = engine.to_json()
        return Outcome(shown=shown)

    def accept(self, env: TaskEnv, db: Session, row: TrialRow, cmd: TrialCommand) -> Outcome:
        if isinstance(cmd, Select):
            return self._select(env, db, row, cmd)
        if isinstance(cmd, Restart):
            return self._restart(env, db, row, cmd)
        if isinstance(cmd, Rate):
            return self._rate(env, db, row, cmd)
        raise StepConflict(f"an evolve trial does not take {cmd.command}")  # pragma: no cover

    def ahead(self, env: TaskEnv, db: Session, row: TrialRow, cmd: TrialCommand) -> None:
        """A selection's next generation (after the last: the final face) made, in a read
        before the write transaction, with its faces' correction kept
        (:func:`emogen.ga.corrector.corrected_ahead`): the write transaction makes the same
        generation from the same stored state and finds its correction made, so the correction
        (most of a dynamic step: the keyframes) runs beside other sessions' steps instead of in
        the one writer. Nothing is stored here."""
        if not isinstance(cmd, Select) or row.status != "active":
            return
        if (cmd.attempt, cmd.generation) != (row.attempt, row.generation):
            return  # not what is shown now: the write transaction says so
        engine = _told(env, row, cmd)
        with corrected_ahead():
            _ = engine.result if engine.done else engine.ask()  # the final face, or the next

    def _select(self, env: TaskEnv, db: Session, row: TrialRow, cmd: Select) -> Outcome:
        """The participant's selection of the shown generation; the next one is stored (or the
        trial waits for its rating)."""
        pop = _shown(db, row, cmd)
        engine = _told(env, row, cmd)
        now = utcnow()
        db.add(
            SelectionRow(
                population_id=pop.id,
                trial_id=row.id,
                elite_face_id=cmd.elite,
                other_face_ids=dumps(list(cmd.others)),
                submitted_at=now,
                server_response_ms=server_ms(now, pop.shown_at, cmd.load_ms),
                client_response_ms=cmd.response_ms,
                load_ms=cmd.load_ms,
                fallback=cmd.fallback,
                step_key=cmd.key,
            )
        )
        row.generation = engine.generation
        row.engine_state = engine.to_json()
        if engine.done:
            row.status = "rating"
            row.final_face_id = int(engine.result.ids[0])
            return Outcome()
        return Outcome(shown=replace(store_population(db, row, engine.ask()), trial=row))

    def _restart(self, env: TaskEnv, db: Session, row: TrialRow, cmd: Restart) -> Outcome:
        """'Start again': a new attempt of the trial at generation 0 (reinitialised or kept)."""
        if not env.config.allow_restart:
            raise StepConflict("this study does not allow starting a trial again")
        pop = _shown(db, row, cmd)
        engine = restore(env, row)
        now = utcnow()
        db.add(
            RestartRow(
                population_id=pop.id,
                trial_id=row.id,
                submitted_at=now,
                server_response_ms=server_ms(now, pop.shown_at, cmd.load_ms),
                client_response_ms=cmd.response_ms,
                load_ms=cmd.load_ms,
                fallback=cmd.fallback,
                step_key=cmd.key,
            )
        )
        shown = store_population(db, row, engine.reset())
        row.attempt = engine.attempt
        row.generation = engine.generation
        row.engine_state = engine.to_json()
        return Outcome(shown=replace(shown, trial=row))

    def _rate(self, env: TaskEnv, db: Session, row: TrialRow, cmd: Rate) -> Outcome:
        """The rating of the trial's final face; the trial is done."""
        points = env.config.rating.points
        if row.status != "rating":
            raise StepConflict(
                f"trial {row.position + 1} is not waiting for a rating (it is at generation "
                f"{row.generation}); reload the page"
            )
        if not 1 <= cmd.value <= points:
            raise SelectionError(f"rating must be an integer in [1, {points}]; got {cmd.value}")
        now = utcnow()
        db.add(
            RatingRow(
                trial_id=row.id,
                face_id=int(row.final_face_id if row.final_face_id is not None else -1),
                value=cmd.value,
                points=points,
                submitted_at=now,
                server_response_ms=elapsed_ms(now, last_selection_time(db, row.id)),
                client_response_ms=cmd.response_ms,
                fallback=cmd.fallback,
                step_key=cmd.key,
            )
        )
        row.status = "done"
        row.finished_at = now
        return Outcome(done=True)

    def view(self, env: TaskEnv, db: Session, row: TrialRow, shown: Any) -> dict[str, Any]:
        return dict(evolve_view(env, db, row, shown))

    def prompt(self, env: TaskEnv, row: TrialRow) -> str:
        return str(env.config.prompt_for(row.emotion))

    def face(
        self, env: TaskEnv, db: Session, row: TrialRow, face_id: int
    ) -> tuple[str, str] | None:
        """A face shown now; a face that moves as the frames of its strip (``face_strip``)."""
        face = shown_face(db, row, face_id)
        if face is None:
            return None
        return face_strip(env, db, row, face) or face.weights, row.identity

    def result(self, env: TaskEnv, db: Session, row: TrialRow) -> dict[str, Any] | None:
        """The emotion made and, once the trial is done, its final face."""
        face = final_face(db, row) if row.status == "done" else None
        final = None if face is None else {"id": face.face_id, "weights": json.loads(face.weights)}
        return {"task": self.name, "emotion": row.emotion, "final_face": final}

    def made_faces(self, db: Session, where: Sequence[Any]) -> list[MadeFace]:
        return final_faces(db, self.name, where)

    def replay(self, env: TaskEnv, db: Session, row: TrialRow, rig: Any) -> Replayed:
        return replay_trial(env, db, row, rig)

    def replay_exported(self, env: TaskEnv, study: ExportedStudy) -> dict[int, list[Replayed]]:
        return replay_export.replay_exported(env, study)

    def export_size(self, db: Session, sessions: Any) -> dict[int, int]:
        """Its faces: the export's largest table."""
        return faces_per_session(db, sessions)

    def simulate(self, who: Any, view: dict[str, Any], trial: int) -> dict[str, Any]:
        """The maker's selection of the shown faces, or their rating of the final face."""
        if view["rating"] is not None:
            face = view["rating"]["face"]
            value = who.maker.rate(
                np.asarray(face["weights"]),
                view["emotion"],
                view["rating"]["points"],
                face.get("motion"),
            )
            return {"command": "rate", "trial": trial, "value": value}
        pop = view["population"]
        faces = pop["faces"]
        limits = (view["limits"]["min_selections"], view["limits"]["max_selections"])
        weights = np.asarray([f["weights"] for f in faces])
        motions = [f.get("motion") for f in faces]
        elite, others = who.maker.select(weights, view["emotion"], limits, motions)
        return {
            "command": "select",
            "trial": trial,
            "attempt": pop["attempt"],
            "generation": pop["generation"],
            "elite": faces[elite]["id"],
            "others": [faces[j]["id"] for j in others],
        }

    def state_facts(self, state: str | None) -> dict[str, Any]:
        """The GA stream and collision solver the trial's engine state was recorded with."""
        if not state:
            return {}
        return {
            "ga_stream": stream_of_state(state),
            "collision_solver": collision_solver_of_state(state),
        }

    def shows(self, block: Any, config: Any) -> dict[str, Any]:
        """The emotions its trials ask for and the identities of their faces (in config order;
        a session's order is its own), the generations after the first, the faces of a
        generation, the selection's limits and the rating's points: all said on the trial's
        screens or in its record (GET /api/s/{token}/trials/{n})."""
        return {
            "emotions": list(block.emotions),
            "identities": list(block.identities),
            "generations": config.ga.generations,
            "faces": config.ga.population_size,
            "min_selections": config.ga.min_selections,
            "max_selections": config.ga.max_selections,
            "rating_points": config.rating.points,
        }

    def progress_step(
        self, status: str, generation: int, generations: int
    ) -> tuple[str, int | None]:
        """Where in the trial the participant is: the generation shown (from 1), or the rating."""
        if status == "rating":
            return "rating", None
        return f"generation {generation + 1} of {generations + 1}", generation + 1

    def notes(self, db: Session, sessions: Any, k: int, block: Any) -> list[str]:
        """Nothing the GA's blocks need say on the dashboard."""
        return []

    def analysis_section(self, tools: Any) -> Any:
        """``emogen analyse``'s section on dynamic blocks' timing
        (:mod:`emogen.tasks.evolve.dynamic_report`); the faces themselves are analysed by
        :mod:`emogen.analysis`."""
        from emogen.tasks.evolve.dynamic_report import dynamic_section

        return dynamic_section(tools)


def _told(env: TaskEnv, row: TrialRow, cmd: Select) -> Any:
    """The trial's engine restored from its stored state and told the selection."""
    engine = restore(env, row)
    engine.tell(cmd.elite, list(cmd.others))
    return engine


def _shown(db: Session, row: TrialRow, cmd: _Shown) -> PopulationRow:
    """The population a selection or restart is for (a conflict if the request is not for what
    the session shows now)."""
    trial = row.position + 1
    if row.status != "active":
        raise StepConflict(
            f"trial {trial} has no generation to select from (it is waiting for the rating); "
            "reload the page"
        )
    if (cmd.attempt, cmd.generation) != (row.attempt, row.generation):
        raise StepConflict(
            f"this request is for generation {cmd.generation} (attempt {cmd.attempt + 1}) of "
            f"trial {trial}, but generation {row.generation} (attempt {row.attempt + 1}) is "
            "shown now; reload the page"
        )
    pop = population_at(db, row.id, row.attempt, row.generation)
    if pop is None:  # pragma: no cover - stored with the engine state
        raise StepConflict("the shown generation was not stored; reload the page")
    return pop
