"""The proof of the task protocol (issue #38): a toy task — rate one face 1–7 — written and
registered in this file alone, with no edit anywhere else, runs a whole simulated study through
``emogen study simulate`` (the real service, database and steps), is exported by ``emogen study
export`` (its own table, typed from its records) and replays with ``emogen replay``; a tampered
record is caught.
"""

from __future__ import annotations

import inspect
import json
import sqlite3
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any, ClassVar, Literal

import numpy as np
import pandas as pd
import pytest
from pydantic import Field
from sqlalchemy import ForeignKey, Integer, String, Text, select
from sqlalchemy.orm import Mapped, Session, mapped_column
from typer.testing import CliRunner
from typing_extensions import TypedDict

from emogen.cli.app import app
from emogen.tasks.blocks import Condition, TaskBlock
from emogen.tasks.export import record_table
from emogen.tasks.protocol import (
    FaceView,
    Outcome,
    Points,
    Replayed,
    TaskDefaults,
    TaskEnv,
    TrialCommand,
)
from emogen.tasks.records import Base, Stamp, TrialRow, dumps, utcnow
from emogen.tasks.registry import register, unregister


# ---- the toy task: everything it takes (fewer than 100 lines) ---------------------------------
class RateFaceBlock(TaskBlock):
    """``faces`` trials, each one random face of the study's first identity to rate."""

    task: Literal["rateface"]
    faces: int = Field(default=3, ge=1, le=50)

    def trials(
        self, k: int, study: Any, earlier: list[Condition], rows: int | None
    ) -> list[Condition]:
        return [Condition(k, self.task, "", study.identities[0], j) for j in range(self.faces)]


class RateFaceRow(Base):
    __tablename__ = "toy_face_ratings"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    trial_id: Mapped[int] = mapped_column(ForeignKey("trials.id"), unique=True)
    value: Mapped[int] = mapped_column(Integer)
    weights: Mapped[str] = mapped_column(Text)
    submitted_at: Mapped[Any] = mapped_column(Stamp)
    step_key: Mapped[str] = mapped_column(String(64))


class RateFace(TrialCommand):
    command: Literal["rate_face"]
    value: Points


class RateFaceView(TypedDict):
    task: Literal["rateface"]
    face: FaceView
    points: int


def toy_face(rig: Any, seed: int) -> list[float]:
    """The trial's face: its shape weights drawn from its seed."""
    return np.random.default_rng(seed).uniform(0.0, 0.6, len(rig.shape_names)).tolist()


class RateFaceResult(TypedDict):
    task: Literal["rateface"]


class RateFaceTask(TaskDefaults):
    name: ClassVar[str] = "rateface"
    block: ClassVar[type[TaskBlock]] = RateFaceBlock
    commands: ClassVar[tuple[type[TrialCommand], ...]] = (RateFace,)
    view_type: ClassVar[type] = RateFaceView
    result_type: ClassVar[type] = RateFaceResult
    tables: ClassVar[tuple[type, ...]] = (RateFaceRow,)
    export_tables: ClassVar[tuple[Any, ...]] = (record_table(RateFaceRow),)
    instructions: ClassVar[str] = "you will rate faces from 1 (not at all) to 7 (very much)."
    screens: ClassVar[dict[str, tuple[float, float]]] = {"face rating": (2.0, 4.0)}

    def screens_of(self, condition: Condition, generations: int) -> dict[str, int]:
        return {"face rating": 1}

    def start(self, env: TaskEnv, db: Session, row: TrialRow, session_id: int) -> Outcome:
        row.status, row.started_at = "active", utcnow()
        row.engine_state = dumps({"weights": toy_face(env.ctx.rig, row.seed)})
        return Outcome()

    def view(self, env: TaskEnv, db: Session, row: TrialRow, shown: Any) -> dict[str, Any]:
        face = {"id": 0, "weights": json.loads(row.engine_state or "{}")["weights"]}
        return {"task": self.name, "face": face, "points": 7}

    def prompt(self, env: TaskEnv, row: TrialRow) -> str:
        return "How much do you like this face?"

    def accept(self, env: TaskEnv, db: Session, row: TrialRow, cmd: TrialCommand) -> Outcome:
        assert isinstance(cmd, RateFace)
        weights = json.loads(row.engine_state or "{}")["weights"]
        db.add(RateFaceRow(trial_id=row.id, value=cmd.value, weights=dumps(weights),
                           submitted_at=utcnow(), step_key=cmd.key))  # fmt: skip
        row.status, row.finished_at = "done", utcnow()
        return Outcome(done=True)

    def replay(self, env: TaskEnv, db: Session, row: TrialRow, rig: Any) -> Replayed:
        stored = db.scalar(select(RateFaceRow.weights).where(RateFaceRow.trial_id == row.id))
        if stored is None:
            return Replayed()
        same = json.loads(stored) == toy_face(rig, row.seed)
        return Replayed(stimuli=1, problems=[] if same else [f"trial {row.position + 1}: face"])

    def simulate(self, who: Any, view: dict[str, Any], trial: int) -> dict[str, Any]:
        value = 1 + round(6 * float(np.mean(view["face"]["weights"])) / 0.6)
        return {"command": "rate_face", "trial": trial, "value": value}


# ---- the end of the toy task ---------------------------------------------------------------------

STUDY = """
name = "toy"
seed = 5
emotions = ["happy", "sad"]
correct = false
ga = {{ generations = 2, min_selections = 1, max_selections = 3 }}
model = "{model}"

[[blocks]]
task = "evolve"

[[blocks]]
task = "rateface"
faces = 3
"""


@pytest.fixture
def toy() -> Iterator[None]:
    register(RateFaceTask())
    yield
    unregister(RateFaceTask.name)
    Base.metadata.remove(Base.metadata.tables[RateFaceRow.__tablename__])


def test_the_toy_task_is_fewer_than_100_lines() -> None:
    source = inspect.getsource(sys.modules[__name__])
    start = source.index("# ---- the toy task")
    end = source.index("# ---- the end of the toy task")
    assert len(source[start:end].splitlines()) < 100


def test_a_toy_task_pilots_exports_and_replays(toy: None, tmp_path: Path, ict_dir: Path) -> None:
    config = tmp_path / "toy.toml"
    config.write_text(STUDY.format(model=ict_dir))
    db = tmp_path / "toy.sqlite"
    url = f"sqlite:///{db}"
    run = CliRunner().invoke
    result = run(app, ["study", "simulate", str(config), "-n", "2", "--seed", "4",
                       "--database-url", url])  # fmt: skip
    assert result.exit_code == 0, result.output
    out = tmp_path / "export"
    result = run(app, ["study", "export", "--database-url", url, "--out", str(out),
                       "--format", "csv"])  # fmt: skip
    assert result.exit_code == 0, result.output
    table = pd.read_csv(out / "toy_face_ratings.csv")
    with sqlite3.connect(db) as con:  # the database itself, read without EmoGen
        stored = pd.read_sql(
            "SELECT s.id AS session_id, s.participant_id, t.position AS trial, r.value, "
            "r.weights FROM toy_face_ratings r JOIN trials t ON t.id = r.trial_id "
            "JOIN sessions s ON s.id = t.session_id ORDER BY s.id, t.position",
            con,
        )
    assert len(table) == len(stored) == 2 * 3  # two participants, three faces each
    cols = ["session_id", "participant_id", "trial", "value"]
    assert table[cols].to_dict("records") == stored[cols].to_dict("records")
    assert table["value"].between(1, 7).all() and set(table["trial"]) == {2, 3, 4}
    trials = pd.read_csv(out / "trials.csv")
    assert (trials["task"] == "rateface").sum() == 6 and (trials["task"] == "evolve").sum() == 4
    result = run(app, ["replay", "1", "--database-url", url, "--json"])
    assert result.exit_code == 0, result.output
    report = json.loads(result.output)  # one session: one report
    assert report["ok"] is True and report["stimuli"] == 3 and report["populations"] == 6
    with sqlite3.connect(db) as con:  # one stored face changed: replay must say so
        con.execute("UPDATE toy_face_ratings SET weights = '[0.5]' WHERE id = 1")
    result = run(app, ["replay", "1", "--database-url", url, "--json"])
    report = json.loads(result.output)
    assert (
        result.exit_code != 0
        and report["ok"] is False
        and report["mismatches"] == ["trial 3: face"]
    )


def test_a_block_of_an_unregistered_task_is_refused_by_name() -> None:
    from emogen.errors import ConfigError
    from emogen.study.config import study_from_dict

    with pytest.raises(ConfigError, match=r"unknown task .rateface.*tasks: evolve, categorise"):
        study_from_dict({"name": "x", "emotions": ["happy"], "blocks": [{"task": "rateface"}]})
