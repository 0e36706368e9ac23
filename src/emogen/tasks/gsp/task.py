"""The ``gsp`` task: Gibbs sampling with people (Harrison et al. 2020, NeurIPS).

A trial gives the participant the furthest-behind free chain of its concept
(:mod:`~emogen.tasks.gsp.chains`) and shows that chain's face with a slider over the chain's
next dimension, starting at a position drawn from the trial's seed; the chosen value replaces
that gene (averaged over ``aggregation`` participants' answers) and the chain moves to its next
node. Where every chain of the concept is held by someone else, the view says ``waiting`` and
the page asks again (``await_chain``) until one is free. The trial's state (its chain, node,
face and the slider's start) is stored when it is given the chain, before it is shown.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from datetime import datetime
from typing import Any, ClassVar, Literal

import numpy as np
from sqlalchemy import func, select
from sqlalchemy.orm import Session

from emogen.errors import ConfigError
from emogen.tasks.blocks import Condition, TaskBlock
from emogen.tasks.errors import StepConflict
from emogen.tasks.gsp import replay_export
from emogen.tasks.gsp.block import GspBlock
from emogen.tasks.gsp.chains import free_chain, lock_concept, locked_chains, make_chains
from emogen.tasks.gsp.export import GSP_TABLES
from emogen.tasks.gsp.replay import replay_trial
from emogen.tasks.gsp.simulated import slide
from emogen.tasks.gsp.tables import GspChainRow, GspIterationRow
from emogen.tasks.gsp.view import (
    GspResult,
    GspView,
    check_position,
    frames_genes,
    full_weights,
    grid,
    gsp_view,
    slider_start,
)
from emogen.tasks.protocol import (
    ExportedStudy,
    Index,
    MadeFace,
    Millis,
    Outcome,
    Replayed,
    TaskEnv,
    TrialCommand,
)
from emogen.tasks.records import TrialRow, dumps, fields_of, numbers_json, server_ms, utcnow


class Slide(TrialCommand):
    """The slider's position sent with "Next" (``fallback``: chosen from the picture strip of a
    page without WebGL)."""

    command: Literal["slide"]
    position: Index
    fallback: bool = False
    load_ms: Millis | None = None


class AwaitChain(TrialCommand):
    """Ask again for a chain while the trial is waiting for one (sent by the page every few
    seconds)."""

    command: Literal["await_chain"]


def _state(row: TrialRow) -> dict[str, Any]:
    return dict(json.loads(row.engine_state or "{}"))


class GspTask:
    """Gibbs sampling with people: one slider answer per trial, chains shared between
    participants (or each participant's own)."""

    name: ClassVar[str] = "gsp"
    block: ClassVar[type[TaskBlock]] = GspBlock
    commands: ClassVar[tuple[type[TrialCommand], ...]] = (Slide, AwaitChain)
    view_type: ClassVar[type] = GspView
    result_type: ClassVar[type] = GspResult
    tables: ClassVar[tuple[type, ...]] = (GspChainRow, GspIterationRow)
    export_tables: ClassVar[tuple[Any, ...]] = GSP_TABLES
    instructions: ClassVar[str] = (
        "you will see one face and a slider under it. Move the slider (or use the arrow keys) "
        "until the face shows the word named above it as well as it can, then press “Next”."
    )
    #: one slider, one face: 5–12 s (Harrison et al. 2020 report no figure; an assumption)
    screens: ClassVar[dict[str, tuple[float, float]]] = {"slider": (5.0, 12.0)}

    def screens_of(self, condition: Condition, generations: int) -> dict[str, int]:
        return {"slider": 1}

    def prepare(self, ctx: Any, k: int, block: GspBlock) -> None:
        """Check the block's dimensions against the rig before anyone starts."""
        try:
            block.check_rig(ctx.rig, ctx.config.ga.eye_motion)
        except ValueError as exc:
            raise ConfigError(f"blocks[{k + 1}].{exc}") from None

    def rows(self, prepared: Any) -> int | None:
        return None

    # ---- a trial ---------------------------------------------------------------------------
    def start(self, env: TaskEnv, db: Session, row: TrialRow, session_id: int) -> Outcome:
        """The trial is given its chain now (or waits for one)."""
        row.status = "active"
        row.started_at = utcnow()
        self._assign(env, db, row, session_id)
        return Outcome()

    def _assign(self, env: TaskEnv, db: Session, row: TrialRow, session_id: int) -> None:
        block: GspBlock = env.block(row)
        owner = session_id if block.chain_scope == "within" else 0
        study_id = min(env.ctx.accepted)
        lock_concept(db, study_id, row.block, row.emotion, owner)
        make_chains(env, db, row, block, owner, study_id)
        chains = locked_chains(db, study_id, row.block, row.emotion, owner)
        chain = free_chain(db, chains, block, session_id)
        if chain is None:
            row.engine_state = dumps({"waiting": True})
            return
        now = utcnow()
        chain.assigned_trial_id, chain.assigned_at = row.id, now
        rig, eye = env.ctx.rig, env.config.ga.eye_motion
        dims = block.dimension_names(rig, eye)
        dimension = dims[chain.iterations % len(dims)]
        row.identity = chain.identity
        row.engine_state = dumps(
            {
                "chain_id": chain.id,
                "chain": chain.chain,
                "iteration": chain.iterations,
                "member": chain.answers,
                "dimension": dimension,
                "dimension_index": rig.gene_names(eye).index(dimension),
                "slider_start": slider_start(row.seed, block.steps),
                "genes": json.loads(chain.genes),
                "assigned_at": now.isoformat(),
            }
        )

    def _frames(self, env: TaskEnv, row: TrialRow, st: dict[str, Any]) -> np.ndarray:
        block: GspBlock = env.block(row)
        genes = frames_genes(np.asarray(st["genes"]), st["dimension_index"], grid(block))
        corrector = env.correctors(row.identity)
        return full_weights(env.ctx.rig, env.config.ga.eye_motion, corrector, genes)

    def accept(self, env: TaskEnv, db: Session, row: TrialRow, cmd: TrialCommand) -> Outcome:
        st = _state(row)
        if isinstance(cmd, AwaitChain):
            if st.get("waiting"):
                self._assign(env, db, row, row.session_id)
            return Outcome()
        if not isinstance(cmd, Slide):  # pragma: no cover - the study checks the command
            raise StepConflict(f"a gsp trial takes slide or await_chain; got {cmd.command}")
        if st.get("waiting") or row.status != "active":
            raise StepConflict(
                f"trial {row.position + 1} has no face to answer yet; reload the page"
            )
        block: GspBlock = env.block(row)
        check_position(block, cmd.position, cmd.fallback)
        self._store(env, db, row, cmd, st, block)
        row.status = "done"
        row.finished_at = utcnow()
        return Outcome(done=True)

    def _store(
        self,
        env: TaskEnv,
        db: Session,
        row: TrialRow,
        cmd: Slide,
        st: dict[str, Any],
        block: GspBlock,
    ) -> None:
        """The answer, and the chain moved where the trial still holds its node."""
        chain = db.get(GspChainRow, st["chain_id"])
        if chain is None:  # pragma: no cover - made before the trial was given it
            raise StepConflict(f"trial {row.position + 1}: its chain is not stored")
        lock_concept(db, chain.study_id, chain.block, chain.emotion, chain.owner)
        db.refresh(chain)  # as the lock's holder before us left it
        applied = (
            chain.assigned_trial_id == row.id
            and chain.iterations == st["iteration"]
            and chain.answers == st["member"]
        )
        value = float(grid(block)[cmd.position])
        before = np.asarray(st["genes"], dtype=np.float64)
        after = before.copy()
        after[st["dimension_index"]] = value
        weights = self._frames(env, row, st)[cmd.position]
        node_value = None
        if applied:
            node_value = self._move(db, chain, block, st, value)
        now = utcnow()
        assigned = datetime.fromisoformat(st["assigned_at"])
        db.add(
            GspIterationRow(
                **fields_of(cmd, GspIterationRow),  # position, fallback, load_ms as sent
                trial_id=row.id,
                chain_id=chain.id,
                iteration=st["iteration"],
                member=st["member"],
                applied=applied,
                applied_key=chain.id if applied else -row.id,
                node_value=node_value,
                dimension=st["dimension"],
                dimension_index=st["dimension_index"],
                slider_start=st["slider_start"],
                slider_value=value,
                genes_before=numbers_json(before.tolist()),
                genes_after=numbers_json(after.tolist()),
                weights_after=numbers_json([float(x) for x in weights]),
                assigned_at=assigned,
                submitted_at=now,
                server_response_ms=server_ms(now, assigned, cmd.load_ms),
                client_response_ms=cmd.response_ms,
                step_key=cmd.key,
            )
        )

    @staticmethod
    def _move(
        db: Session, chain: GspChainRow, block: GspBlock, st: dict[str, Any], value: float
    ) -> float | None:
        """Count the answer at the chain's node; where it completes the node, the chain's gene
        takes the node's mean answer and the chain moves on. The node's value, if complete."""
        chain.assigned_trial_id, chain.assigned_at = None, None
        chain.answers += 1
        if chain.answers < block.aggregation:
            return None
        earlier = db.scalars(
            select(GspIterationRow.slider_value).where(
                GspIterationRow.chain_id == chain.id,
                GspIterationRow.iteration == st["iteration"],
                GspIterationRow.applied.is_(True),
            )
        ).all()
        node = float(np.mean([*earlier, value]))
        genes = json.loads(chain.genes)
        genes[st["dimension_index"]] = node
        chain.genes = numbers_json(genes)
        chain.iterations += 1
        chain.answers = 0
        return node

    def view(self, env: TaskEnv, db: Session, row: TrialRow, shown: Any) -> dict[str, Any]:
        st = _state(row)
        block: GspBlock = env.block(row)
        if st.get("waiting") or "chain_id" not in st:
            return dict(gsp_view(block, row.emotion, None, None))
        return dict(gsp_view(block, row.emotion, self._frames(env, row, st), st["slider_start"]))

    def prompt(self, env: TaskEnv, row: TrialRow) -> str:
        text = env.block(row).prompt or env.config.prompt
        return str(text).replace("{EMOTION}", row.emotion.upper()).replace("{emotion}", row.emotion)

    def face(
        self, env: TaskEnv, db: Session, row: TrialRow, face_id: int
    ) -> tuple[str, str] | None:
        """A slider position's face (the fallback strip's pictures), while the trial shows it."""
        st = _state(row)
        block: GspBlock = env.block(row)
        if row.status != "active" or "chain_id" not in st or not 0 <= face_id < block.steps:
            return None
        weights = self._frames(env, row, st)[face_id]
        return numbers_json([float(x) for x in weights]), row.identity

    def result(self, env: TaskEnv, db: Session, row: TrialRow) -> dict[str, Any] | None:
        it = _iteration(db, row)
        if row.status != "done" or it is None:
            return None
        return {
            "task": self.name,
            "emotion": row.emotion,
            "position": it.position,
            "value": it.slider_value,
            "slider_start": it.slider_start,
            "weights": json.loads(it.weights_after),
        }

    def made_faces(self, db: Session, where: Sequence[Any]) -> list[MadeFace]:
        """The face each applied answer made (the concept's chain node as this participant
        left it)."""
        rows = db.execute(
            select(TrialRow, GspIterationRow)
            .join(GspIterationRow, GspIterationRow.trial_id == TrialRow.id)
            .where(TrialRow.status == "done", GspIterationRow.applied.is_(True), *where)
            .order_by(TrialRow.session_id, TrialRow.position)
        ).all()
        return [
            {
                "session_id": t.session_id,
                "trial": t.position,
                "condition": t.condition,
                "emotion": t.emotion,
                "identity": t.identity,
                "face_id": it.position,
                "genes": json.loads(it.genes_after),
                "weights": json.loads(it.weights_after),
            }
            for t, it in rows
        ]

    def replay(self, env: TaskEnv, db: Session, row: TrialRow, rig: Any) -> Replayed:
        return replay_trial(env, db, row, rig)

    def simulate(self, who: Any, view: dict[str, Any], trial: int) -> dict[str, Any]:
        """Waiting: ask again. Else the position the participant's prototype of the concept
        picks (:meth:`emogen.tasks.simulated.SimulatedParticipant.slide`)."""
        if view["waiting"]:
            return {"command": "await_chain", "trial": trial}
        frames = np.asarray(view["frames"], dtype=np.float64)
        position = slide(who.maker, frames, view["emotion"])
        return {"command": "slide", "trial": trial, "position": position}

    def state_facts(self, state: str | None) -> dict[str, Any]:
        return {}

    def analysis_section(self, tools: Any) -> Any:
        """``emogen analyse``'s section on the export's GSP chains
        (:mod:`emogen.tasks.gsp.analysis_report`)."""
        from emogen.tasks.gsp.analysis_report import gsp_section

        return gsp_section(tools)

    def progress_step(
        self, status: str, generation: int, generations: int
    ) -> tuple[str, int | None]:
        return self.name, None

    #: the chains (seeds, initial faces) and every answer (:mod:`.replay_export`)
    replay_tables: ClassVar[tuple[str, ...]] = replay_export.TABLES

    def replay_exported(self, env: TaskEnv, study: ExportedStudy) -> dict[int, list[Replayed]]:
        """Every chain rebuilt from its seed and the exported answers; each answer compared
        (:mod:`emogen.tasks.gsp.replay_export`)."""
        return replay_export.replay_exported(env, study)

    def export_size(self, db: Session, sessions: Any) -> dict[int, int]:
        """An iteration row per trial answered."""
        query = (
            select(TrialRow.session_id, func.count(GspIterationRow.id))
            .join(GspIterationRow, GspIterationRow.trial_id == TrialRow.id)
            .where(TrialRow.session_id.in_(sessions))
            .group_by(TrialRow.session_id)
        )
        return {int(sid): int(n) for sid, n in db.execute(query)}

    def notes(self, db: Session, sessions: Any, k: int, block: Any) -> list[str]:
        return []

    def shows(self, block: Any, config: Any) -> dict[str, Any]:
        """The concepts its trials name, the slider's positions and range: what the page shows
        (never the chain's state, which another participant's answer may change)."""
        return {
            "emotions": list(block.emotions or config.emotions),
            "steps": block.steps,
            "slider": list(block.slider),
        }


def _iteration(db: Session, row: TrialRow) -> GspIterationRow | None:
    return db.scalar(select(GspIterationRow).where(GspIterationRow.trial_id == row.id))
