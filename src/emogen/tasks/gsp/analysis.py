"""What GSP chains found: each chain's faces node by node, the chain aggregate per concept with
bootstrap intervals over chains, convergence, and comparisons (between concepts; with the GA's
mean final face of the same emotion).

Faces are compared in gene space (the ``g_<gene>`` columns): ED, the Euclidean distance, and
CD = 1 − a·b / (‖a‖ ‖b‖), the paper's cosine distance (eq. 12), on genes. A chain is the unit
of the aggregate's intervals (Harrison et al. 2020 average the chains' last states); a
participant is the unit of the GA's mean face, as everywhere in ``emogen analyse``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np
import pandas as pd

from emogen.metrics.basic import cosine_distance

#: Bootstrap resamples of every interval.
BOOTSTRAP = 2000


@dataclass(frozen=True)
class Chains:
    """One concept's chains: ``states[c]`` (nodes + 1, n_genes) — the chain's face before its
    first node, then after each complete node — its identity, and the gene names."""

    block_name: str
    emotion: str
    chain_ids: list[int]
    states: list[np.ndarray]
    identities: list[str]
    genes: list[str]

    @property
    def finals(self) -> np.ndarray:
        """(chains, n_genes): each chain's last face."""
        return np.stack([s[-1] for s in self.states])


def gene_columns(table: pd.DataFrame) -> list[str]:
    return [c for c in table.columns if c.startswith("g_")]


def chains_of(iterations: pd.DataFrame) -> list[Chains]:
    """Every concept's chains from a ``gsp_iterations`` table: a chain's face after node n is
    its face before node n with the node's gene at ``node_value`` (a plain loop from the
    face before node 0). Chains without a complete node are left out (they hold their random
    start only)."""
    cols = gene_columns(iterations)
    applied = iterations[iterations["applied"].astype(bool)]
    out = []
    for (block, emotion), rows in applied.groupby(["block_name", "emotion"], sort=True):
        ids, states, idents = [], [], []
        for chain_id, chain in rows.groupby("chain_id", sort=True):
            chain = chain.sort_values(["iteration", "member"])
            complete = chain[chain["node_value"].notna()]
            if complete.empty:
                continue
            face = np.asarray(json.loads(chain["genes_before"].iloc[0]), dtype=np.float64)
            walk = [face.copy()]
            dims = complete["dimension_index"].to_numpy(dtype=np.int64)
            values = complete["node_value"].to_numpy(dtype=np.float64)
            for dim, value in zip(dims, values, strict=True):
                face[dim] = value
                walk.append(face.copy())
            ids.append(int(str(chain_id)))
            states.append(np.stack(walk))
            idents.append(str(chain["identity"].iloc[0]))
        if ids:
            genes = [c.removeprefix("g_") for c in cols]
            out.append(Chains(str(block), str(emotion), ids, states, idents, genes))
    return out


def boot_rows(n: int, rng: np.random.Generator) -> np.ndarray:
    """(BOOTSTRAP, n) row indices drawn with replacement."""
    return rng.integers(0, n, size=(BOOTSTRAP, n))


def aggregate(chains: Chains, rng: np.random.Generator, alpha: float) -> pd.DataFrame:
    """The chain aggregate (the mean of the chains' last faces) per gene, with its percentile
    bootstrap interval over chains."""
    finals = chains.finals
    boots = finals[boot_rows(len(finals), rng)].mean(axis=1)
    lo, hi = np.quantile(boots, [alpha / 2, 1 - alpha / 2], axis=0)
    return pd.DataFrame(
        {
            "block_name": chains.block_name,
            "emotion": chains.emotion,
            "gene": chains.genes,
            "mean": finals.mean(axis=0),
            "ci_low": lo,
            "ci_high": hi,
            "n_chains": len(finals),
        }
    )


def _mean_pairwise(faces: np.ndarray) -> float:
    diffs = faces[:, None, :] - faces[None, :, :]
    d = np.linalg.norm(diffs, axis=2)
    n = len(faces)
    return float(d.sum() / (n * (n - 1))) if n > 1 else float("nan")


def convergence(chains: Chains) -> pd.DataFrame:
    """Per node count n (0: the chains' starts): the chains that reached n, their mean pairwise
    ED, and their mean ED to the final aggregate."""
    target = chains.finals.mean(axis=0)
    longest = max(len(s) for s in chains.states)
    rows = []
    for n in range(longest):
        faces = np.stack([s[n] for s in chains.states if len(s) > n])
        rows.append(
            {
                "block_name": chains.block_name,
                "emotion": chains.emotion,
                "iteration": n,
                "n_chains": len(faces),
                "between_chains": _mean_pairwise(faces),
                "to_aggregate": float(np.linalg.norm(faces - target, axis=1).mean()),
            }
        )
    return pd.DataFrame(rows)


def compare(
    a: np.ndarray, b: np.ndarray, rng: np.random.Generator, alpha: float
) -> dict[str, float]:
    """CD and ED between the means of two sets of faces (rows: the units, chains or
    participants), each with a percentile bootstrap interval resampling each set's units."""
    ma = a[boot_rows(len(a), rng)].mean(axis=1)
    mb = b[boot_rows(len(b), rng)].mean(axis=1)
    cd = cosine_distance(ma, mb)
    ed = np.linalg.norm(ma - mb, axis=1)
    mean_a, mean_b = a.mean(axis=0), b.mean(axis=0)
    q = [alpha / 2, 1 - alpha / 2]
    return {
        "cd": float(cosine_distance(mean_a[None, :], mean_b[None, :])[0]),
        "cd_low": float(np.quantile(cd, q[0])),
        "cd_high": float(np.quantile(cd, q[1])),
        "ed": float(np.linalg.norm(mean_a - mean_b)),
        "ed_low": float(np.quantile(ed, q[0])),
        "ed_high": float(np.quantile(ed, q[1])),
    }


def participant_means(final_faces: pd.DataFrame, emotion: str, genes: list[str]) -> np.ndarray:
    """(participants, n_genes): each participant's mean final GA face of ``emotion`` (the
    participant is the unit); empty where none."""
    rows = final_faces[final_faces["emotion"] == emotion]
    cols = [f"g_{g}" for g in genes]
    if rows.empty or not set(cols) <= set(rows.columns):
        return np.zeros((0, len(genes)))
    return rows.groupby("participant_id")[cols].mean().to_numpy(dtype=np.float64)
