"""The ``categorise`` task in a session: its block's faces drawn and stored when the block
starts, one face shown per trial, the answer stored before the server answers.

When a session reaches a categorise block, every trial of the block gets its face at once
(:meth:`CategoriseTrials.draw_block`): the participant's own finished faces (in the config
order of the evolve trials they were made in), other participants' finished faces (from the
sessions of this study completed by then, balanced over the labels; a fallback face where too
few exist), rows of a face table, or random draws. The draws use a generator seeded by the
block's trials' recorded seeds, and each trial's label order one seeded by the trial's seed, so
a session's stimuli replay (:mod:`emogen.study.replay`).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from sqlalchemy import select
from sqlalchemy.orm import Session

from emogen.errors import ConfigError
from emogen.model.face_table import read_face_table
from emogen.study.config import StudyConfig
from emogen.study.context import StudyContext
from emogen.study.errors import StepConflict
from emogen.study.tables import (
    FaceRow,
    PopulationRow,
    ResponseRow,
    SessionRow,
    StimulusRow,
    TrialRow,
    dumps,
    numbers_json,
    utcnow,
)
from emogen.study.weights import StudyCorrectors
from emogen.study.writes import Timing, server_ms
from emogen.tasks.blocks import CategoriseBlock
from emogen.tasks.categorise import CategoriseView, categorise_view, check_answer
from emogen.tasks.protocol import FaceView
from emogen.tasks.sources import balanced_pick, label_order, pick_rows, random_faces

#: The face id a categorise trial's one face has in its view (and its PNG's URL).
FACE_ID = 0


@dataclass(frozen=True)
class FileFaces:
    """A face table's rows: shape weights (n, n_shapes), and per row its identity (or None)
    and its label (the emotion it was made for, or None)."""

    path: Path
    weights: np.ndarray
    identities: list[str | None]
    labels: list[str | None]


def _column(frame: object, names: tuple[str, ...]) -> list[str | None] | None:
    cols = {str(c).lower(): c for c in getattr(frame, "columns", [])}
    for name in names:
        if name in cols:
            values = frame[cols[name]].tolist()  # type: ignore[index]
            return [None if v is None or str(v).strip() in ("", "nan") else str(v).strip()
                    for v in values]  # fmt: skip
    return None


def read_file_faces(path: Path, ctx: StudyContext, where: str) -> FileFaces:
    """A categorise block's face table (``file`` or ``others_fallback``), checked: its rows'
    identities must be the study's (errors name the block key, the file and the row)."""
    table = read_face_table(
        path, ctx.rig, what=where, label_columns=("label", "emotion", "identity")
    )
    n = len(table.weights)
    identities = _column(table.frame, ("identity",)) or [None] * n
    labels = _column(table.frame, ("label", "emotion")) or [None] * n
    known = set(ctx.config.all_identities())
    for row, name in enumerate(identities):
        if name is not None and name not in known:
            raise ConfigError(
                f"{where} {path} row {row + 1}: identity {name!r} is not one of the study's "
                f"identities ({', '.join(sorted(known))})"
            )
    return FileFaces(path, table.weights, identities, labels)


def file_rows(files: dict[tuple[int, str], FileFaces]) -> dict[int, int]:
    """Rows of each block's ``file`` (the trials of a block without ``file_faces``)."""
    return {k: len(f.weights) for (k, key), f in files.items() if key == "file"}


def block_files(ctx: StudyContext) -> dict[tuple[int, str], FileFaces]:
    """Every categorise block's face tables, read once when the service starts."""
    out: dict[tuple[int, str], FileFaces] = {}
    for k, block in enumerate(ctx.config.study_blocks()):
        if not isinstance(block, CategoriseBlock):
            continue
        for key in ("file", "others_fallback"):
            path = getattr(block, key)
            if path is not None:
                out[(k, key)] = read_file_faces(Path(path), ctx, f"blocks[{k + 1}].{key}")
    return out


@dataclass
class _Face:
    """A face picked for a trial, before it is stored."""

    source: str
    identity: str
    weights: list[float]
    genes: list[float] | None = None
    intended: str | None = None
    fallback: bool = False
    source_session_id: int | None = None
    source_trial: int | None = None
    source_face_id: int | None = None
    source_row: int | None = None
    source_label: str | None = None


class CategoriseTrials:
    """Starts, shows and answers a session's categorise trials (the task's runner)."""

    task = "categorise"

    def __init__(
        self,
        ctx: StudyContext,
        correctors: StudyCorrectors,
        files: dict[tuple[int, str], FileFaces],
    ) -> None:
        self.ctx = ctx
        self.correctors = correctors
        self.blocks = ctx.config.study_blocks()
        self.files = files

    def block(self, index: int) -> CategoriseBlock:
        block = self.blocks[index]
        if not isinstance(block, CategoriseBlock):  # pragma: no cover - trials made from it
            raise StepConflict(f"block {index + 1} is not a categorise block")
        return block

    # ---- starting a trial ------------------------------------------------------------------
    def start(self, db: Session, sess: SessionRow, row: TrialRow) -> None:
        """The trial is shown now: its block's faces drawn first if they are not yet."""
        stim = db.scalar(select(StimulusRow).where(StimulusRow.trial_id == row.id))
        if stim is None:
            self.draw_block(db, sess, row.block)
            stim = db.scalar(select(StimulusRow).where(StimulusRow.trial_id == row.id))
        now = utcnow()
        row.status = "active"
        row.started_at = now
        if stim is not None:
            stim.shown_at = now

    def draw_block(self, db: Session, sess: SessionRow, block_index: int) -> None:
        """Pick and store the faces of every trial of the session's block ``block_index``."""
        block = self.block(block_index)
        trials = list(
            db.scalars(
                select(TrialRow)
                .where(TrialRow.session_id == sess.id, TrialRow.block == block_index)
                .order_by(TrialRow.condition)
            )
        )
        rng = np.random.default_rng([int(t.seed) for t in trials])
        by_source: dict[str, list[TrialRow]] = {}
        for t in trials:
            by_source.setdefault(self._source(t), []).append(t)
        picked: dict[int, _Face] = {}
        for source in ("own", "other", "file", "random"):
            rows = by_source.get(source, [])
            if rows:
                faces = getattr(self, f"_{source}")(db, sess, block, block_index, len(rows), rng)
                picked.update({t.id: f for t, f in zip(rows, faces, strict=True)})
        for t in trials:
            face = picked[t.id]
            offered = label_order(block.labels or (), np.random.default_rng(int(t.seed)))
            t.emotion = face.intended or ""
            t.identity = face.identity
            db.add(StimulusRow(
                trial_id=t.id, source=face.source, fallback=face.fallback,
                source_session_id=face.source_session_id, source_trial=face.source_trial,
                source_face_id=face.source_face_id, source_row=face.source_row,
                source_label=face.source_label, intended=face.intended, identity=face.identity,
                genes=None if face.genes is None else numbers_json(face.genes),
                weights=numbers_json(face.weights), labels=dumps(offered),
            ))  # fmt: skip
        db.flush()

    def _source(self, t: TrialRow) -> str:
        conditions = self.ctx.conditions
        return conditions[t.condition].source if t.condition < len(conditions) else "random"

    def _own(
        self, db: Session, sess: SessionRow, block: CategoriseBlock, index: int, n: int,
        rng: np.random.Generator,
    ) -> list[_Face]:  # fmt: skip
        """The session's finished faces of the evolve trials before the block, in the config
        order of their conditions."""
        found = _final_faces(db, (TrialRow.session_id == sess.id, TrialRow.block < index))
        found.sort(key=lambda f: f[0].condition)
        return [_stored_face("own", t, face) for t, face in found[:n]]

    def _other(
        self, db: Session, sess: SessionRow, block: CategoriseBlock, index: int, n: int,
        rng: np.random.Generator,
    ) -> list[_Face]:  # fmt: skip
        """Finished faces of other participants' completed sessions, balanced over the labels;
        a fallback face (the block's ``others_fallback`` rows, else random) where too few."""
        done = select(SessionRow.id).where(
            SessionRow.study_id.in_(self.ctx.accepted),
            SessionRow.stage == "done",
            SessionRow.id != sess.id,
        )
        found = _final_faces(db, (TrialRow.session_id.in_(done),))
        found.sort(key=lambda f: (f[0].session_id, f[0].position))
        picks = balanced_pick([t.emotion for t, _ in found], block.labels or (), n, rng)
        missing = sum(p is None for p in picks)
        spare = iter(self._fallback(block, index, missing, rng) if missing else [])
        return [_stored_face("other", *found[p]) if p is not None else next(spare) for p in picks]

    def _fallback(
        self, block: CategoriseBlock, index: int, n: int, rng: np.random.Generator
    ) -> list[_Face]:
        table = self.files.get((index, "others_fallback"))
        faces = (
            self._table_faces(table, block, n, rng, "other")
            if table is not None
            else self._random(None, None, block, index, n, rng, source="other")
        )
        for face in faces:
            face.fallback = True
        return faces

    def _file(
        self, db: Session, sess: SessionRow, block: CategoriseBlock, index: int, n: int,
        rng: np.random.Generator,
    ) -> list[_Face]:  # fmt: skip
        return self._table_faces(self.files[(index, "file")], block, n, rng, "file")

    def _table_faces(
        self, table: FileFaces, block: CategoriseBlock, n: int, rng: np.random.Generator,
        source: str,
    ) -> list[_Face]:  # fmt: skip
        rows = pick_rows(len(table.weights), n, rng)
        idents = block.identities or self.ctx.config.identities
        faces = []
        for k, r in enumerate(rows):
            identity = table.identities[r] or idents[k % len(idents)]
            full = self._full(table.weights[r : r + 1], identity)
            faces.append(_Face(source, identity, full, intended=table.labels[r], source_row=r))
        return faces

    def _random(
        self, db: Session | None, sess: SessionRow | None, block: CategoriseBlock, index: int,
        n: int, rng: np.random.Generator, source: str = "random",
    ) -> list[_Face]:  # fmt: skip
        ga = self.ctx.config.ga
        genes, made = random_faces(self.ctx.rig, ga, kind=block.random_kind, n=n,
                                   genes_range=block.random_genes, rng=rng)  # fmt: skip
        weights = self.ctx.rig.expand(genes, ga.eye_motion)
        idents = block.identities or self.ctx.config.identities
        faces = []
        for k in range(n):
            identity = idents[k % len(idents)]
            full = self._full(weights[k : k + 1], identity)
            faces.append(_Face(source, identity, full, genes=genes[k].tolist(),
                               source_label=made[k]))  # fmt: skip
        return faces

    def _full(self, weights: np.ndarray, identity: str) -> list[float]:
        """A face's full weights: its shape weights, then its correctives (corrected studies)."""
        corrector = self.correctors(identity)
        w = np.asarray(weights, dtype=np.float64)
        if corrector is not None:
            _, extra = corrector(w)
            w = np.hstack([w, np.asarray(extra, dtype=np.float64).reshape(len(w), -1)])
        if not np.isfinite(w).all():
            raise ValueError("a face to store has non-finite weights")
        return [float(x) for x in w[0]]

    # ---- the answer -------------------------------------------------------------------------
    def respond(
        self, db: Session, row: TrialRow, *, key: str, label: str, intensity: int | None,
        confidence: int | None, timing: Timing,
    ) -> None:  # fmt: skip
        """Store the answer to the trial's face (checked against the labels it offered)."""
        stim = db.scalar(select(StimulusRow).where(StimulusRow.trial_id == row.id))
        if stim is None:  # pragma: no cover - stored when the trial started
            raise StepConflict(f"trial {row.position + 1} has no face stored; reload the page")
        block = self.block(row.block)
        position = check_answer(block, json.loads(stim.labels), label, intensity, confidence)
        now = utcnow()
        db.add(ResponseRow(
            trial_id=row.id, label=label, label_position=position, intensity=intensity,
            confidence=confidence, submitted_at=now,
            server_response_ms=server_ms(now, stim.shown_at, timing.load_ms),
            client_response_ms=timing.response_ms, load_ms=timing.load_ms, step_key=key,
        ))  # fmt: skip
        row.status = "done"
        row.finished_at = now


def categorise_state(db: Session, config: StudyConfig, row: TrialRow) -> CategoriseView | None:
    """What the participant is shown of a categorise trial: its face and the labels in their
    order (never the face's source or the emotion it was made for)."""
    stim = db.scalar(select(StimulusRow).where(StimulusRow.trial_id == row.id))
    block = config.study_blocks()[row.block]
    if stim is None or not isinstance(block, CategoriseBlock):
        return None
    face: FaceView = {"id": FACE_ID, "weights": json.loads(stim.weights)}
    return categorise_view(block, face, json.loads(stim.labels))


def _final_faces(db: Session, where: tuple[object, ...]) -> list[tuple[TrialRow, FaceRow]]:
    """(trial, final face) of the finished evolve trials matching ``where``: the final face's
    row in the trial's last attempt (its latest generation, where it was shown again)."""
    rows = db.execute(
        select(TrialRow, FaceRow)
        .join(PopulationRow, PopulationRow.trial_id == TrialRow.id)
        .join(FaceRow, FaceRow.population_id == PopulationRow.id)
        .where(
            *where,  # type: ignore[arg-type]
            TrialRow.task == "evolve",
            TrialRow.status == "done",
            PopulationRow.attempt == TrialRow.attempt,
            FaceRow.face_id == TrialRow.final_face_id,
        )
        .order_by(PopulationRow.generation)
    ).all()
    latest = {t.id: (t, f) for t, f in rows}  # the last generation's row wins
    return list(latest.values())


def _stored_face(source: str, trial: TrialRow, face: FaceRow) -> _Face:
    return _Face(
        source, trial.identity, json.loads(face.weights), genes=json.loads(face.genes),
        intended=trial.emotion, source_session_id=trial.session_id, source_trial=trial.position,
        source_face_id=face.face_id,
    )  # fmt: skip
