"""A GSP block's chains: made once per study (or per session, ``chain_scope = "within"``),
each started from a seeded face of the protocol initialisation, and given out node by node.

**Which chain a trial gets.** The free chain of its concept that is furthest behind (fewest
complete nodes, then fewest answers at the current node, then the lowest index). A chain is
free when no trial holds its current node, or the trial holding it has not answered within
``release_after`` seconds (it is then given to the next participant: the late answer is kept
but does not move the chain). A participant does not get the chain their previous trial of the
concept extended (unless ``repeat_chain``), nor a node they have answered already (aggregation).

**Exactly once.** Every step that makes, assigns or moves a concept's chains first takes the
concept's lock (:func:`emogen.tasks.records.lock_shared`: a transaction-level advisory lock on
PostgreSQL, after the session's row lock; SQLite runs one writing transaction at a time), then
reads the chains afresh: two first participants arriving at once make the chains once, two
participants never get the same node, and an answer moves the chain it was given only if that
node is still its own. The database holds the last line: a chain's key is unique, and so is an
applied answer's (chain, node, member).
"""

from __future__ import annotations

from collections.abc import Sequence
from datetime import datetime, timedelta
from typing import Any

import numpy as np
from sqlalchemy import and_, func, select
from sqlalchemy.orm import Session

from emogen.model.rig import Rig
from emogen.tasks.categorise.sources import random_faces
from emogen.tasks.gsp.block import GspBlock
from emogen.tasks.gsp.tables import GspChainRow, GspIterationRow
from emogen.tasks.records import TrialRow, as_utc, lock_shared, numbers_json, utcnow


def chain_seed(study_seed: int | None, block: int, emotion: int, chain: int, owner: int) -> int:
    """A chain's seed: from the study's seed, the block, the concept, the chain and its owner
    (a fresh one where the study has no seed; recorded either way)."""
    if study_seed is None:
        return int(np.random.SeedSequence().generate_state(1, np.uint64)[0] >> 1)
    words = [study_seed, block, emotion, chain, owner]
    return int(np.random.SeedSequence(words).generate_state(1, np.uint64)[0] >> 1)


def initial_face(
    rig: Rig, ga: Any, block: GspBlock, dims: Sequence[str], seed: int
) -> tuple[np.ndarray, str]:
    """A chain's first face (genes) and what made it: the first face of a protocol
    initialisation population drawn from the chain's seed (the neutral face left out, as a
    categorise block's random faces are drawn), its genes outside the slider's
    dimensions set to 0 and those inside clipped to the slider's range."""
    names = rig.gene_names(ga.eye_motion)
    genes, labels = random_faces(
        rig, ga, kind="protocol", n=1, genes_range=(1, 1), rng=np.random.default_rng(seed)
    )
    moved = np.isin(np.asarray(names), np.asarray(dims))
    lo, hi = block.slider
    face = np.where(moved, np.clip(genes[0], lo, hi), 0.0)
    return face, labels[0]


def lock_concept(db: Session, study_id: int, block: int, emotion: str, owner: int) -> None:
    """Hold the lock of a concept's chains until the step's transaction ends."""
    lock_shared(db, "gsp", study_id, block, emotion, owner)


def make_chains(
    env: Any, db: Session, row: TrialRow, block: GspBlock, owner: int, study_id: int
) -> None:
    """The concept's chains of this block, made where they are not yet (under the concept's
    lock: once, whoever asks first)."""
    made = db.scalar(
        select(func.count())
        .select_from(GspChainRow)
        .where(
            GspChainRow.study_id == study_id,
            GspChainRow.block == row.block,
            GspChainRow.emotion == row.emotion,
            GspChainRow.owner == owner,
        )
    )
    if made:
        return
    rig, ga = env.ctx.rig, env.config.ga
    dims = block.dimension_names(rig, ga.eye_motion)
    concepts = list(block.emotions or ())
    idents = block.identities or env.config.identities
    now = utcnow()
    for c in range(block.chains):
        seed = chain_seed(env.config.seed, row.block, concepts.index(row.emotion), c, owner)
        face, label = initial_face(rig, ga, block, dims, seed)
        genes = numbers_json([float(x) for x in face])
        db.add(
            GspChainRow(
                trial_id=row.id,
                study_id=study_id,
                block=row.block,
                emotion=row.emotion,
                chain=c,
                owner=owner,
                seed=seed,
                identity=idents[c % len(idents)],
                source_label=label,
                initial_genes=genes,
                genes=genes,
                iterations=0,
                answers=0,
                created_at=now,
            )
        )
    db.flush()


def locked_chains(
    db: Session, study_id: int, block: int, emotion: str, owner: int
) -> list[GspChainRow]:
    """The concept's chains (the concept's lock held), read afresh, in chain order."""
    query = (
        select(GspChainRow)
        .where(
            GspChainRow.study_id == study_id,
            GspChainRow.block == block,
            GspChainRow.emotion == emotion,
            GspChainRow.owner == owner,
        )
        .order_by(GspChainRow.chain)
        .execution_options(populate_existing=True)
    )
    return list(db.scalars(query))


def held(chain: GspChainRow, release_after: float, now: datetime) -> bool:
    """Whether a trial holds the chain's current node (assigned, within ``release_after``)."""
    at = as_utc(chain.assigned_at)
    if chain.assigned_trial_id is None or at is None:
        return False
    return now - at < timedelta(seconds=release_after)


def _history(db: Session, session_id: int, chain_ids: list[int]) -> tuple[int | None, set[Any]]:
    """The chain the session's latest answer of these chains extended, and the (chain, node)
    pairs it has answered."""
    rows = db.execute(
        select(GspIterationRow.chain_id, GspIterationRow.iteration, TrialRow.position)
        .join(TrialRow, TrialRow.id == GspIterationRow.trial_id)
        .where(and_(TrialRow.session_id == session_id, GspIterationRow.chain_id.in_(chain_ids)))
    ).all()
    latest = max(rows, key=lambda r: r[2])[0] if rows else None
    return latest, {(r[0], r[1]) for r in rows}


def free_chain(
    db: Session, chains: list[GspChainRow], block: GspBlock, session_id: int
) -> GspChainRow | None:
    """The chain a trial of this session gets now (None: every chain is held, or is one the
    session may not extend now)."""
    now = utcnow()
    latest, answered = _history(db, session_id, [c.id for c in chains])
    free = [
        c
        for c in chains
        if not held(c, block.release_after, now)
        and (block.repeat_chain or c.id != latest)
        and (c.id, c.iterations) not in answered
    ]
    if not free:
        return None
    return min(free, key=lambda c: (c.iterations, c.answers, c.chain))
