"""Replay of a session's categorise trials: every stored face checked against where it came from.

* the labels' order: drawn again from the trial's recorded seed (exact);
* an own or other face: its genes are those of the face it names (the session, trial and face
  id recorded), as stored there (exact), and its weights within rounding of that face's;
* a random face: its genes expanded by the rig and corrected again (the shape weights and
  correctives within floating-point rounding of those stored, :mod:`emogen.study.rounding`: a
  few ULPs on another CPU pass, a real change — a wrong gene, another correction — does not);
* a file face: its shape weights are the row of the block's face table, when that file is
  readable here (else said not checked, with why).

Which faces a block drew (which other sessions, which rows) is recorded, not re-drawn: the pool
of other participants' faces depends on the sessions completed when the block started.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
from sqlalchemy import select
from sqlalchemy.orm import Session

from emogen.errors import EmoGenError
from emogen.model.rig import Rig
from emogen.tasks.categorise.block import CategoriseBlock
from emogen.tasks.categorise.faces import face_table_at, table_of
from emogen.tasks.categorise.sources import label_order
from emogen.tasks.categorise.tables import StimulusRow
from emogen.tasks.protocol import Replayed, TaskEnv
from emogen.tasks.records import TrialRow, numbers_json
from emogen.tasks.rounding import WEIGHT_TOLERANCE, weight_deviation, within_rounding

Checked = tuple[list[str], float]  # problems, largest weight deviation
#: the start of a "problem" that is something not checked (said apart from the differences)
NOT_CHECKED = "not checked: "


def check_stimulus(env: TaskEnv, db: Session, trial: TrialRow, rig: Rig) -> Replayed:
    """A categorise trial's stored face checked against its source (faces checked, problems,
    largest weight deviation)."""
    n, problems, deviation = _check(env, db, trial, rig)
    unchecked = [p for p in problems if p.startswith(NOT_CHECKED)]
    problems = [p for p in problems if not p.startswith(NOT_CHECKED)]
    return Replayed(
        stimuli=n,
        problems=problems,
        deviation=deviation,
        checked={"categorised faces": n} if n else {},
        unchecked=[p[len(NOT_CHECKED) :] for p in unchecked],
    )


def _check(env: TaskEnv, db: Session, trial: TrialRow, rig: Rig) -> tuple[int, list[str], float]:
    config, correctors = env.config, env.correctors
    stim = db.scalar(select(StimulusRow).where(StimulusRow.trial_id == trial.id))
    where = f"trial {trial.position + 1} ({stim.source if stim else 'no'} face)"
    if stim is None:
        return 0, [], 0.0  # the block not reached yet
    blocks = config.study_blocks()
    block = blocks[trial.block] if trial.block < len(blocks) else None
    if not isinstance(block, CategoriseBlock):
        return 0, [f"{where}: block {trial.block + 1} of the config is not a categorise block"], 0.0
    problems = []
    expected = label_order(block.labels or (), np.random.default_rng(int(trial.seed)))
    if json.loads(stim.labels) != expected:
        problems.append(f"{where}: labels offered {stim.labels}, the seed gives {expected}")
    weights = np.asarray(json.loads(stim.weights), dtype=np.float64)
    checked: Checked = [], 0.0
    if stim.source_face_id is not None:
        checked = _made_face(env, db, stim, weights, where)
    elif stim.genes is not None:
        genes = np.asarray(json.loads(stim.genes), dtype=np.float64)[None, :]
        shapes = rig.expand(genes, config.ga.eye_motion)
        checked = _compare(where, weights, _corrected(shapes, stim.identity, correctors))
    elif stim.source_row is not None:
        checked = _file_face(block, stim, rig, weights, where)
    return 1, problems + checked[0], checked[1]


def _made_face(
    env: TaskEnv, db: Session, stim: StimulusRow, weights: np.ndarray, where: str
) -> Checked:
    source = (
        TrialRow.session_id == stim.source_session_id,
        TrialRow.position == stim.source_trial,
    )
    found = [f for f in env.made_faces(db, source) if f["face_id"] == stim.source_face_id]
    made = (
        None if not found else (numbers_json(found[0]["weights"]), numbers_json(found[0]["genes"]))
    )
    if made is None:
        return [
            f"{where}: its source face (session {stim.source_session_id}, trial "
            f"{(stim.source_trial or 0) + 1}, face {stim.source_face_id}) is not stored"
        ], 0.0
    if made[1] != stim.genes:
        return [f"{where}: genes differ from its source face"], 0.0
    problems, worst = _compare(where, weights, np.asarray(json.loads(made[0]), dtype=np.float64))
    return [
        p.replace("weights differ", "weights differ from its source face") for p in problems
    ], worst


def _file_face(
    block: CategoriseBlock, stim: StimulusRow, rig: Rig, weights: np.ndarray, where: str
) -> Checked:
    path = block.file
    if stim.source == "other":
        path = block.others_fallback if stim.fallback else block.others_pool
    if path is None or not Path(path).exists():
        return [
            f"{NOT_CHECKED}{where}: its weights (row {(stim.source_row or 0) + 1} of {path}) not checked: the table is not here"
        ], 0.0
    try:
        path = table_of(Path(path))
        table = face_table_at(path, rig, "face table")
    except EmoGenError as exc:
        return [f"{where}: cannot read its face table: {exc}"], 0.0
    row = int(stim.source_row or 0)
    if row >= len(table.weights):
        return [f"{where}: row {row + 1} is beyond the {len(table.weights)} rows of {path}"], 0.0
    return _compare(where, weights[: table.weights.shape[1]], table.weights[row])


def _corrected(shapes: np.ndarray, identity: str, correctors: Any) -> np.ndarray:
    corrector = correctors(identity)
    face = np.asarray(shapes[0], dtype=np.float64)
    if corrector is None:
        return face
    _, extra = corrector(shapes)
    return np.concatenate([face, np.asarray(extra, dtype=np.float64).reshape(-1)])


def _compare(where: str, stored: np.ndarray, replayed: np.ndarray) -> Checked:
    if stored.shape != replayed.shape:
        return [f"{where}: {stored.size} weights stored, replay made {replayed.size}"], 0.0
    worst = weight_deviation(stored, replayed)
    if not within_rounding(worst):
        return [
            f"{where}: weights differ by up to {worst:.3g} (tolerance {WEIGHT_TOLERANCE:g})"
        ], worst
    return [], worst
