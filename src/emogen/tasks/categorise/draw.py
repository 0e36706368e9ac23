"""A categorise block's faces, drawn and stored for all its trials when a session reaches it.

Every trial of the block gets its face at once: the participant's own finished faces (in the
config order of the trials they were made in), other participants' finished faces (from the
sessions of this study completed by then, balanced over the labels; a fallback face where too
few exist), rows of a face table, or random draws. The draws use a generator seeded by the
block's trials' recorded seeds, and each trial's label order one seeded by the trial's seed, so
a session's stimuli replay (:mod:`emogen.tasks.categorise.replay`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from sqlalchemy import select
from sqlalchemy.orm import Session

from emogen.tasks.categorise.block import CategoriseBlock
from emogen.tasks.categorise.faces import FileFaces
from emogen.tasks.categorise.sources import balanced_pick, label_order, pick_rows, random_faces
from emogen.tasks.categorise.tables import StimulusRow
from emogen.tasks.protocol import MadeFace, TaskEnv
from emogen.tasks.records import TrialRow, dumps, numbers_json


@dataclass
class Picked:
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


class BlockDraw:
    """The draw of one session's categorise block (``k``) of ``env``'s study."""

    def __init__(self, env: TaskEnv, db: Session, session_id: int, k: int) -> None:
        self.env, self.db, self.session_id, self.k = env, db, session_id, k
        self.block: CategoriseBlock = env.config.study_blocks()[k]
        self.files: dict[str, FileFaces] = env.prepared.get(k) or {}

    def store(self) -> None:
        """Pick and store the faces of every trial of the block."""
        trials = list(
            self.db.scalars(
                select(TrialRow)
                .where(TrialRow.session_id == self.session_id, TrialRow.block == self.k)
                .order_by(TrialRow.condition)
            )
        )
        rng = np.random.default_rng([int(t.seed) for t in trials])
        by_source: dict[str, list[TrialRow]] = {}
        for t in trials:
            by_source.setdefault(self._source(t), []).append(t)
        picked: dict[int, Picked] = {}
        draws = {"own": self._own, "other": self._other, "file": self._file}
        for source in ("own", "other", "file", "random"):
            rows = by_source.get(source, [])
            if rows:
                faces = draws.get(source, self._random)(len(rows), rng)
                picked.update({t.id: f for t, f in zip(rows, faces, strict=True)})
        for t in trials:
            self._add(t, picked[t.id])
        self.db.flush()

    def _add(self, t: TrialRow, face: Picked) -> None:
        offered = label_order(self.block.labels or (), np.random.default_rng(int(t.seed)))
        t.emotion = face.intended or ""
        t.identity = face.identity
        self.db.add(
            StimulusRow(
                trial_id=t.id,
                source=face.source,
                fallback=face.fallback,
                source_session_id=face.source_session_id,
                source_trial=face.source_trial,
                source_face_id=face.source_face_id,
                source_row=face.source_row,
                source_label=face.source_label,
                intended=face.intended,
                identity=face.identity,
                genes=None if face.genes is None else numbers_json(face.genes),
                weights=numbers_json(face.weights),
                labels=dumps(offered),
            )
        )

    def _source(self, t: TrialRow) -> str:
        conditions = self.env.ctx.conditions
        return conditions[t.condition].source if t.condition < len(conditions) else "random"

    def _own(self, n: int, rng: np.random.Generator) -> list[Picked]:
        """The session's finished faces of the trials before the block, in the config order of
        their conditions."""
        where = (TrialRow.session_id == self.session_id, TrialRow.block < self.k)
        found = sorted(self.env.made_faces(self.db, where), key=lambda f: f["condition"])
        return [_made("own", face) for face in found[:n]]

    def _other(self, n: int, rng: np.random.Generator) -> list[Picked]:
        """Finished faces of other participants' completed sessions, balanced over the labels;
        a fallback face (the block's ``others_fallback`` rows, else random) where too few."""
        done = self.env.sessions_done(self.session_id)
        found = self.env.made_faces(self.db, (TrialRow.session_id.in_(done),))
        found.sort(key=lambda f: (f["session_id"], f["trial"]))
        pool = self.files.get("others_pool")
        emotions = [f["emotion"] for f in found] + [str(x) for x in (pool.labels if pool else [])]
        picks = balanced_pick(emotions, self.block.labels or (), n, rng)
        missing = sum(p is None for p in picks)
        spare = iter(self._fallback(missing, rng) if missing else [])
        out = []
        for p in picks:
            if p is None:
                out.append(next(spare))
            elif p < len(found) or pool is None:
                out.append(_made("other", found[p]))
            else:
                out.append(self._row_face(pool, p - len(found), p, "other"))
        return out

    def _fallback(self, n: int, rng: np.random.Generator) -> list[Picked]:
        table = self.files.get("others_fallback")
        faces = (
            self._table_faces(table, n, rng, "other")
            if table is not None
            else self._random(n, rng, source="other")
        )
        for face in faces:
            face.fallback = True
        return faces

    def _file(self, n: int, rng: np.random.Generator) -> list[Picked]:
        return self._table_faces(self.files["file"], n, rng, "file")

    def _table_faces(
        self, table: FileFaces, n: int, rng: np.random.Generator, source: str
    ) -> list[Picked]:
        rows = pick_rows(len(table.weights), n, rng)
        return [self._row_face(table, r, k, source) for k, r in enumerate(rows)]

    def _row_face(self, table: FileFaces, r: int, k: int, source: str) -> Picked:
        """Row ``r`` of a face table, the ``k``-th face drawn (a row without an identity takes
        the block's identities in turn)."""
        idents = self.block.identities or self.env.config.identities
        identity = table.identities[r] or idents[k % len(idents)]
        full = self._full(table.weights[r : r + 1], identity)
        return Picked(source, identity, full, intended=table.labels[r], source_row=r)

    def _random(self, n: int, rng: np.random.Generator, source: str = "random") -> list[Picked]:
        ga, rig = self.env.config.ga, self.env.ctx.rig
        genes, made = random_faces(
            rig, ga, kind=self.block.random_kind, n=n, genes_range=self.block.random_genes, rng=rng
        )
        weights = rig.expand(genes, ga.eye_motion)
        idents = self.block.identities or self.env.config.identities
        faces = []
        for k in range(n):
            identity = idents[k % len(idents)]
            full = self._full(weights[k : k + 1], identity)
            faces.append(
                Picked(source, identity, full, genes=genes[k].tolist(), source_label=made[k])
            )
        return faces

    def _full(self, weights: np.ndarray, identity: str) -> list[float]:
        """A face's full weights: its shape weights, then its correctives (corrected studies)."""
        corrector = self.env.correctors(identity)
        w = np.asarray(weights, dtype=np.float64)
        if corrector is not None:
            _, extra = corrector(w)
            w = np.hstack([w, np.asarray(extra, dtype=np.float64).reshape(len(w), -1)])
        if not np.isfinite(w).all():
            raise ValueError("a face to store has non-finite weights")
        return [float(x) for x in w[0]]


def _made(source: str, face: MadeFace) -> Picked:
    return Picked(
        source,
        face["identity"],
        face["weights"],
        genes=face["genes"],
        intended=face["emotion"],
        source_session_id=face["session_id"],
        source_trial=face["trial"],
        source_face_id=face["face_id"],
    )
