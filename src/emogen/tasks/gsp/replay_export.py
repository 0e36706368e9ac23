"""Replay of GSP chains from exported files alone (``emogen study replay --from-export``).

Every chain of ``gsp_chains`` is rebuilt from its seed and the answers of ``gsp_iterations``,
in node order: its seed drawn again from the study's seed (where the study has one), its
initial face from its seed (:func:`~emogen.tasks.gsp.chains.initial_face`), then node by node
the node's gene (the block's dimensions in turn) set to the mean of its ``aggregation`` applied
answers. Each answer is compared with the chain so rebuilt: the face before it, the gene moved,
the slider's start (drawn again from the trial's seed, ``trials``), the value at the chosen
position, the node's value, the face chosen (``g_`` columns) and its full weights (``w_``
columns, expanded and corrected again). Discrete things exactly; numbers within
floating-point rounding (:mod:`emogen.tasks.rounding`: a few ULPs on another CPU pass, a changed
answer does not). A node missing from a chain, an answered trial without its answer, and an
answer whose chain is not exported are named. Each difference names the session, trial, chain,
node and field, with the recorded and the rebuilt value.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from emogen.tasks.gsp.block import GspBlock
from emogen.tasks.gsp.chains import chain_seed, initial_face
from emogen.tasks.gsp.view import full_weights, grid, slider_start
from emogen.tasks.protocol import ExportedStudy, Replayed, TaskEnv
from emogen.tasks.rounding import WEIGHT_TOLERANCE, weight_deviation, within_rounding

#: the export tables a gsp replay reads
TABLES = ("gsp_iterations", "gsp_chains")
Key = tuple[int, int]  # session_id, trial
Record = dict[Any, Any]  # a table row


def _na(v: Any) -> bool:
    return v is None or bool(pd.isna(v))


@dataclass(frozen=True)
class Chain:
    """A chain as its answers are checked against it: its name in messages, its identity, its
    block and the genes its nodes move in turn."""

    label: str
    identity: str
    block: GspBlock
    dims: tuple[str, ...]


@dataclass
class Rebuild:
    """What one study's replay found, by trial (and the chain-level findings by session)."""

    env: TaskEnv
    study: ExportedStudy
    seeds: dict[Key, int]
    by_trial: dict[Key, Replayed] = field(default_factory=dict)
    #: each chain's own findings (seed, initial face), with the session that made it
    by_chain: dict[int, tuple[int, Replayed]] = field(default_factory=dict)

    def of(self, key: Key) -> Replayed:
        return self.by_trial.setdefault(key, Replayed())

    def close(
        self, where: str, what: str, recorded: Any, rebuilt: Any, names: list[str] | None = None
    ) -> list[str]:
        """A difference beyond rounding between a recorded and a rebuilt number or face
        (``names``: its entries' names; default the genes')."""
        a = np.atleast_1d(np.asarray(recorded, dtype=np.float64))
        b = np.atleast_1d(np.asarray(rebuilt, dtype=np.float64))
        if a.shape != b.shape:
            return [f"{where}: {what} has {a.size} values recorded, the rebuilt chain {b.size}"]
        worst = weight_deviation(a, b)
        if within_rounding(worst):
            return []
        if a.size == 1:
            return [f"{where}: {what} recorded {a[0]:.12g}, rebuilt {b[0]:.12g}"]
        return [
            f"{where}: {what}: recorded and rebuilt differ by up to {worst:.3g} (tolerance "
            f"{WEIGHT_TOLERANCE:g}); at {self._at(a, b, names)}"
        ]

    def _at(self, a: np.ndarray, b: np.ndarray, names: list[str] | None) -> str:
        """Where two arrays differ most: the entry's name, recorded and rebuilt value."""
        i = int(np.argmax(np.where(a == b, 0.0, np.abs(a - b))))
        names = self.study.genes if names is None else names
        name = names[i] if a.size == len(names) else f"#{i}"
        return f"{name}: recorded {a[i]:.12g}, rebuilt {b[i]:.12g}"


def replay_exported(env: TaskEnv, study: ExportedStudy) -> dict[int, list[Replayed]]:
    """Every exported gsp answer of ``study.sessions`` checked against its chain rebuilt from
    the chain's seed and the exported answers: by session id, in trial order."""
    trials = study.trials_of("gsp")
    if trials.empty:
        return {}
    lacking = study.missing("gsp", TABLES)
    if lacking is not None:
        return lacking
    seeds = {(int(r.session_id), int(r.trial)): int(r.seed) for r in trials.itertuples()}
    work = Rebuild(env, study, seeds)
    answers = study.tables["gsp_iterations"]
    chains = study.tables["gsp_chains"]
    for chain in chains.sort_values("chain_id").to_dict("records"):
        rows = answers[answers["chain_id"] == chain["chain_id"]]
        _chain(work, chain, rows)
    known = set(chains["chain_id"].astype(int))
    answered = {(int(a.session_id), int(a.trial)) for a in answers.itertuples()}
    for r in answers[~answers["chain_id"].isin(known)].itertuples():
        where = f"session {r.session_id} trial {int(r.trial) + 1}"
        work.of((int(r.session_id), int(r.trial))).problems.append(
            f"{where}: its chain (chain_id {r.chain_id}) is not in gsp_chains"
        )
    for r in trials.itertuples():
        key = (int(r.session_id), int(r.trial))
        if str(r.status) == "done" and key not in answered:
            work.of(key).problems.append(
                f"session {key[0]} trial {key[1] + 1}: answered (status done) but its answer "
                "is not in gsp_iterations"
            )
    out: dict[int, list[Replayed]] = {}
    for key in sorted(work.by_trial):
        if key[0] in study.sessions:
            out.setdefault(key[0], []).append(work.by_trial[key])
    for chain_id, (maker, found) in sorted(work.by_chain.items()):
        mine = answers.loc[answers["chain_id"] == chain_id, "session_id"].astype(int)
        to = maker if maker in study.sessions else min(set(mine) & study.sessions, default=None)
        if to is not None:  # the maker's, else the first replayed session's that answered it
            out.setdefault(to, []).append(found)
    return out


def _chain(work: Rebuild, chain: Record, rows: pd.DataFrame) -> None:
    """Rebuild one chain node by node and check every answer to it."""
    config, rig = work.study.config, work.study.rig
    eye = config.ga.eye_motion
    block = config.study_blocks()[int(chain["block"])]
    label = f"{chain['emotion']} chain {int(chain['chain'])}"
    found = Replayed(checked={"gsp chains": 1})
    work.by_chain[int(chain["chain_id"])] = (int(chain["made_by_session_id"]), found)
    if not isinstance(block, GspBlock):
        found.problems.append(f"{label}: block {int(chain['block']) + 1} is not a gsp block")
        return
    dims = block.dimension_names(rig, eye)
    owner = 0 if _na(chain["chain_owner_session_id"]) else int(chain["chain_owner_session_id"])
    if config.seed is not None:
        concept = list(block.emotions or ()).index(str(chain["emotion"]))
        seed = chain_seed(config.seed, int(chain["block"]), concept, int(chain["chain"]), owner)
        if seed != int(chain["seed"]):
            found.problems.append(
                f"{label}: seed recorded {chain['seed']}, the study's seed gives {seed}"
            )
    start, _ = initial_face(rig, config.ga, block, dims, int(chain["seed"]))
    initial = json.loads(str(chain["initial_genes"]))
    found.problems += work.close(label, "initial_genes (its initial face)", initial, start)
    about = Chain(label, str(chain["identity"]), block, dims)
    applied = rows[rows["applied"].astype(bool)].sort_values(["iteration", "member"])
    befores: dict[int, np.ndarray] = {}
    genes = start.copy()
    expected = 0
    for at, members in applied.groupby("iteration", sort=True):
        node = int(str(at))
        first = members.to_dict("records")[0]
        where = (
            f"session {first['session_id']} trial {int(first['trial']) + 1} ({label}, node {node})"
        )
        recorded = np.asarray(json.loads(str(first["genes_before"])), dtype=np.float64)
        if node != expected:
            gap = f"node {expected}" if node == expected + 1 else f"nodes {expected}–{node - 1}"
            why = [
                f"{where}: {gap} not in the export (the answer before this is node {expected - 1}'s)"
            ]
        else:
            why = work.close(where, "genes_before", recorded, genes)
        if why:  # named once, where the chain parts from its rebuild; it goes on from there
            work.of((int(first["session_id"]), int(first["trial"]))).problems += [
                f"{why[0]}; the chain is rebuilt on from this recorded face"
            ]
            genes = recorded.copy()
        befores[node] = genes.copy()
        values = _node(work, about, node, members, genes)
        if len(values) == block.aggregation:
            genes[rig.gene_names(eye).index(dims[node % len(dims)])] = float(np.mean(values))
        expected = node + 1
    for r in rows[~rows["applied"].astype(bool)].to_dict("records"):
        node = int(r["iteration"])
        key = (int(r["session_id"]), int(r["trial"]))
        if node in befores:
            _answer(work, about, r, befores[node], None)
        else:
            work.of(key).problems.append(
                f"session {key[0]} trial {key[1] + 1} ({label}, node {node}): a late answer "
                "to a node the chain has no applied answer for"
            )


def _value(block: GspBlock, r: Record) -> float:
    """An answer's value: the slider's value at its position (the participant's answer); the
    recorded value where the position is off the slider (named as such by :func:`_answer`)."""
    position = int(r["position"])
    if 0 <= position < block.steps:
        return float(grid(block)[position])
    return float(r["slider_value"])


def _node(
    work: Rebuild, chain: Chain, node: int, members: pd.DataFrame, before: np.ndarray
) -> list[float]:
    """Check a node's applied answers; the values that count towards it."""
    block = chain.block
    records = members.to_dict("records")
    got = [int(r["member"]) for r in records]
    if got != list(range(len(records))) or len(records) > block.aggregation:
        first = (int(records[0]["session_id"]), int(records[0]["trial"]))
        work.of(first).problems.append(
            f"{chain.label}, node {node}: members {got} recorded, the block's aggregation = "
            f"{block.aggregation} gives {list(range(block.aggregation))}"
        )
    values = [_value(block, r) for r in records][: block.aggregation]
    for k, r in enumerate(records):
        complete = k == block.aggregation - 1
        _answer(work, chain, r, before, float(np.mean(values)) if complete else None)
    return values


def _answer(
    work: Rebuild, chain: Chain, r: Record, before: np.ndarray, node_value: float | None
) -> None:
    """Check one answer against its chain as rebuilt (``before``: the face before its node;
    ``node_value``: the node's mean, on the answer that completes it)."""
    block = chain.block
    key = (int(r["session_id"]), int(r["trial"]))
    node = int(r["iteration"])
    where = f"session {key[0]} trial {key[1] + 1} ({chain.label}, node {node})"
    found = work.of(key)
    found.checked["gsp answers"] = found.checked.get("gsp answers", 0) + 1
    found.stimuli += 1
    found.faces += 1
    bad = found.problems
    rig, config = work.study.rig, work.study.config
    names = rig.gene_names(config.ga.eye_motion)
    dimension = chain.dims[node % len(chain.dims)]
    for what, recorded, rebuilt in (
        ("identity", str(r["identity"]), chain.identity),
        ("dimension", str(r["dimension"]), dimension),
        ("dimension_index", int(r["dimension_index"]), names.index(dimension)),
        ("aggregation", int(r["aggregation"]), block.aggregation),
    ):
        if recorded != rebuilt:
            bad.append(f"{where}: {what} recorded {recorded}, rebuilt {rebuilt}")
    if key in work.seeds:
        start = slider_start(work.seeds[key], block.steps)
        if int(r["slider_start"]) != start:
            bad.append(
                f"{where}: slider_start recorded {r['slider_start']}, the seed gives {start}"
            )
    else:
        found.unchecked.append(f"{where}: slider_start not checked: the trial is not in trials")
    position = int(r["position"])
    if not 0 <= position < block.steps:
        bad.append(f"{where}: position {position} is off the slider's {block.steps} positions")
        return
    value = float(grid(block)[position])
    d = names.index(dimension)
    bad += work.close(where, f"slider_value (position {position})", r["slider_value"], value)
    bad += work.close(where, "genes_before", json.loads(str(r["genes_before"])), before)
    bad += work.close(where, "value_before", r["value_before"], before[d])
    recorded_node = None if _na(r["node_value"]) else float(r["node_value"])
    if (recorded_node is None) != (node_value is None):
        bad.append(f"{where}: node_value recorded {recorded_node}, rebuilt {node_value}")
    elif node_value is not None:
        bad += work.close(where, "node_value", recorded_node, node_value)
    after = before.copy()
    after[d] = value
    genes = [r[f"g_{g}"] for g in work.study.genes]
    bad += work.close(where, "g_ columns (the face chosen)", genes, after)
    corrector = work.env.correctors(str(r["identity"]))
    weights = full_weights(rig, config.ga.eye_motion, corrector, after)[0]
    shown = np.asarray([r[f"w_{w}"] for w in work.study.weights], dtype=np.float64)
    if shown.shape == weights.shape:
        found.deviation = max(found.deviation, weight_deviation(shown, weights))
    bad += work.close(where, "w_ columns (its weights)", shown, weights, work.study.weights)
