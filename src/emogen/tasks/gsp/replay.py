"""Replay of a GSP trial: its chain rebuilt from the chain's seed and the recorded answers.

For the trial's answer: the chain's initial face is drawn again from its recorded seed (and
that seed from the study's seed, where it has one); the face before the answer is the initial
face with every earlier complete node's value applied, in node order (each node's value the
mean of its applied answers); the gene moved is the block's dimension at that node; the
slider's start is drawn again from the trial's seed; the value is the slider's value at the
chosen position; the chosen face's weights are expanded (and corrected) again — within
floating-point rounding (:mod:`emogen.tasks.rounding`); everything discrete exactly.
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np
from sqlalchemy import select
from sqlalchemy.orm import Session

from emogen.tasks.gsp.block import GspBlock
from emogen.tasks.gsp.chains import chain_seed, initial_face
from emogen.tasks.gsp.tables import GspChainRow, GspIterationRow
from emogen.tasks.gsp.view import full_weights, grid, slider_start
from emogen.tasks.protocol import Replayed, TaskEnv
from emogen.tasks.records import TrialRow
from emogen.tasks.rounding import WEIGHT_TOLERANCE, weight_deviation, within_rounding


def _differs(problems: list[str], where: str, what: str, stored: Any, replayed: Any) -> float:
    """Compare float arrays within rounding; a problem naming ``what`` where they differ."""
    a = np.asarray(stored, dtype=np.float64)
    b = np.asarray(replayed, dtype=np.float64)
    if a.shape != b.shape:
        problems.append(f"{where}: {what} has {a.size} values stored, replay made {b.size}")
        return 0.0
    worst = weight_deviation(a, b)
    if not within_rounding(worst):
        problems.append(
            f"{where}: {what} differs by up to {worst:.3g} (tolerance {WEIGHT_TOLERANCE:g})"
        )
    return worst


def chain_before(db: Session, chain: GspChainRow, iteration: int) -> np.ndarray:
    """The chain's face before node ``iteration``: its initial genes with the earlier complete
    nodes' values applied (each the mean of its applied answers, as recorded)."""
    genes = np.asarray(json.loads(chain.initial_genes), dtype=np.float64)
    answers = db.scalars(
        select(GspIterationRow)
        .where(
            GspIterationRow.chain_id == chain.id,
            GspIterationRow.applied.is_(True),
            GspIterationRow.iteration < iteration,
        )
        .order_by(GspIterationRow.iteration, GspIterationRow.member)
    ).all()
    nodes: dict[int, list[GspIterationRow]] = {}
    for a in answers:
        nodes.setdefault(a.iteration, []).append(a)
    for node in sorted(nodes):
        values = [a.slider_value for a in nodes[node]]
        genes[nodes[node][0].dimension_index] = float(np.mean(values))
    return genes


def _node_mean(db: Session, chain: GspChainRow, iteration: int) -> float:
    values = db.scalars(
        select(GspIterationRow.slider_value).where(
            GspIterationRow.chain_id == chain.id,
            GspIterationRow.iteration == iteration,
            GspIterationRow.applied.is_(True),
        )
    ).all()
    return float(np.mean(values))


def replay_trial(env: TaskEnv, db: Session, row: TrialRow, rig: Any) -> Replayed:
    it = db.scalar(select(GspIterationRow).where(GspIterationRow.trial_id == row.id))
    if it is None:
        return Replayed()  # not answered yet
    chain = db.get(GspChainRow, it.chain_id)
    where = f"trial {row.position + 1} (chain {chain.chain if chain else '?'}, node {it.iteration})"
    block = env.block(row)
    if chain is None or not isinstance(block, GspBlock):
        return Replayed(stimuli=1, problems=[f"{where}: its chain or its gsp block is missing"])
    problems: list[str] = []
    config, eye = env.config, env.config.ga.eye_motion
    owner_seed = (
        chain_seed(
            config.seed,
            chain.block,
            list(block.emotions or ()).index(chain.emotion),
            chain.chain,
            chain.owner,
        )
        if config.seed is not None
        else chain.seed
    )
    if owner_seed != chain.seed:
        problems.append(f"{where}: chain seed {chain.seed}, the study's seed gives {owner_seed}")
    dims = block.dimension_names(rig, eye)
    first, _ = initial_face(rig, config.ga, block, dims, int(chain.seed))
    worst = _differs(
        problems, where, "the chain's initial face", json.loads(chain.initial_genes), first
    )
    before = chain_before(db, chain, it.iteration)
    worst = max(
        worst, _differs(problems, where, "the face before", json.loads(it.genes_before), before)
    )
    dimension = dims[it.iteration % len(dims)]
    if it.dimension != dimension:
        problems.append(f"{where}: dimension {it.dimension}, the chain's order gives {dimension}")
    start = slider_start(row.seed, block.steps)
    if it.slider_start != start:
        problems.append(f"{where}: slider start {it.slider_start}, the seed gives {start}")
    value = float(grid(block)[it.position]) if 0 <= it.position < block.steps else float("nan")
    if it.slider_value != value:
        problems.append(f"{where}: value {it.slider_value}, position {it.position} is {value}")
    completes = it.applied and it.member == block.aggregation - 1
    node = _node_mean(db, chain, it.iteration) if completes else None
    if not (
        it.node_value == node
        or (
            node is not None
            and it.node_value is not None
            and abs(it.node_value - node) <= WEIGHT_TOLERANCE
        )
    ):
        problems.append(f"{where}: node value {it.node_value}, its answers give {node}")
    after = before.copy()
    after[rig.gene_names(eye).index(dimension)] = value
    worst = max(
        worst, _differs(problems, where, "the chosen face", json.loads(it.genes_after), after)
    )
    weights = full_weights(rig, eye, env.correctors(row.identity), after)[0]
    worst = max(
        worst,
        _differs(
            problems, where, "the chosen face's weights", json.loads(it.weights_after), weights
        ),
    )
    checked = {"gsp answers": 1}
    return Replayed(stimuli=1, faces=1, problems=problems, deviation=worst, checked=checked)
