"""What chance gives: baselines for the replication's findings.

Where a finding reads final faces (repeatability bins, the intensity line, the nose ratio), its
chance level is the same statistic on faces with no target behind them: faces as protocol
initialisation draws them (:func:`chance_faces`).

Table I's accuracies are read against the same clusters with the target labels permuted (a
permutation distribution of the Hungarian-matched accuracy and of the adjusted Rand index):
with no relation between target and cluster, how many samples would a one-to-one matching of
clusters to targets still call correct?
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from scipy.optimize import linear_sum_assignment

if TYPE_CHECKING:
    from emogen.model.rig import Rig


def contingency(labels: np.ndarray, predicted: np.ndarray) -> np.ndarray:
    """Samples per (label, cluster): (n_labels, n_clusters)."""
    y, p = np.asarray(labels, dtype=np.int64), np.asarray(predicted, dtype=np.int64)
    if y.shape != p.shape or y.ndim != 1 or len(y) == 0:
        raise ValueError(f"labels and clusters must be equal 1-d arrays; got {y.shape}, {p.shape}")
    if y.min() < 0 or p.min() < 0:
        raise ValueError("labels and clusters must be indices ≥ 0")
    table = np.zeros((y.max() + 1, p.max() + 1), dtype=np.int64)
    np.add.at(table, (y, p), 1)
    return table


def matched_clusters(labels: np.ndarray, predicted: np.ndarray) -> np.ndarray:
    """The cluster matched one-to-one to each label (Hungarian, most samples kept); −1 for a
    label left without a cluster (fewer clusters than labels)."""
    table = contingency(labels, predicted)
    rows, cols = linear_sum_assignment(table, maximize=True)
    out = np.full(table.shape[0], -1, dtype=np.int64)
    out[rows] = cols
    return out


def matched_correct(labels: np.ndarray, predicted: np.ndarray) -> np.ndarray:
    """Per sample: 1 when it lies in the cluster matched one-to-one to its label, else 0 (two
    labels lumped into one cluster: one of them is wrong)."""
    y = np.asarray(labels, dtype=np.int64)
    return (np.asarray(predicted) == matched_clusters(y, predicted)[y]).astype(np.int64)


@dataclass(frozen=True)
class Chance:
    """Matched accuracy and ARI with the labels permuted: their 95th percentiles and means
    (``permutations`` draws)."""

    accuracy_mean: float
    accuracy_95: float
    ari_mean: float
    ari_95: float
    permutations: int

    def text(self) -> str:
        return (
            f"chance (labels permuted, {self.permutations}×): matched accuracy "
            f"{self.accuracy_mean:.1%} (95th percentile {self.accuracy_95:.1%}), ARI "
            f"{self.ari_mean:+.3f} (95th percentile {self.ari_95:+.3f})"
        )


def permutation_chance(
    labels: np.ndarray, predicted: np.ndarray, rng: np.random.Generator, permutations: int = 200
) -> Chance:
    """The permutation distribution of the matched accuracy and ARI of ``predicted`` against
    ``labels`` shuffled by ``rng``."""
    from sklearn.metrics import adjusted_rand_score

    if permutations < 1:
        raise ValueError(f"permutations must be ≥ 1; got {permutations}")
    y = np.asarray(labels, dtype=np.int64)
    acc, ari = np.empty(permutations), np.empty(permutations)
    for i in range(permutations):
        shuffled = rng.permutation(y)
        acc[i] = matched_correct(shuffled, predicted).mean()
        ari[i] = adjusted_rand_score(shuffled, predicted)
    return Chance(
        float(acc.mean()),
        float(np.quantile(acc, 0.95)),
        float(ari.mean()),
        float(np.quantile(ari, 0.95)),
        permutations,
    )


def chance_faces(rig: Rig, count: int, rng: np.random.Generator) -> np.ndarray:
    """What chance gives where a finding reads final faces: ``count`` faces (count, S) as
    protocol initialisation draws them (one non-neutral face of each of ``count`` fresh
    generation-0 populations, full weights) — faces with no target behind them."""
    from emogen.ga.init import NEUTRAL, protocol_init

    if count < 1:
        raise ValueError(f"count must be ≥ 1; got {count}")
    faces = []
    for _ in range(count):
        genes, labels = protocol_init(rig, rng=rng)
        keep = np.flatnonzero(labels != NEUTRAL)
        faces.append(genes[rng.choice(keep)])
    return np.asarray(rig.expand(np.stack(faces)))
