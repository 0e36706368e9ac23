"""Section IV-B2: "the selective acute sensitivity to errors in some components makes std_ED
unsuitable for efficient data clustering within a distribution".

Each metric clusters in its own geometry: ED(β) in the PCA coordinates β, std_ED(β) in β / σ
(each component divided by its training SD), CD(α) in α / |α| (the chord between unit vectors:
chord² = 2 CD). A *spherical* Gaussian mixture (isotropic clusters: balls of the metric; a
full-covariance mixture would undo the metric's weighting) with one component per group is
fitted in each geometry; a sample is correct when it lies in the cluster matched one-to-one to
its group (Hungarian, :func:`~emogen.analysis.replication.baselines.matched_correct`). The
same samples are clustered in every geometry, so the metrics' correctness pairs up per sample.

Two readings of "within a distribution": the final faces of Table I's setting (a CD observer
toward targets 1, 2, 3) and the simulated participants' final faces of the four emotions —
the training distribution itself. Chance: std_ED's clusters with the labels permuted.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from emogen.analysis.replication.baselines import Chance, matched_correct, permutation_chance
from emogen.analysis.replication.findings import Finding
from emogen.analysis.replication.intervals import Direction, Evidence, judged
from emogen.analysis.replication.verdicts import readings_parts_verdict

if TYPE_CHECKING:
    from emogen.metrics import PCASpace

GEOMETRIES = {"pca_ed": "ED(β)", "std_ed": "std_ED(β)", "cd": "CD(α)"}


@dataclass(frozen=True, eq=False)
class Clustering:
    """One reading: per metric, per sample 1 when matched to its group (``correct``), and the
    permutation chance of std_ED's clusters."""

    reading: str
    correct: dict[str, np.ndarray]
    chance: Chance

    def rows(self) -> list[dict[str, object]]:
        return [
            {
                "samples": self.reading,
                "geometry": GEOMETRIES[m],
                "matched accuracy": float(c.mean()),
                "chance (labels permuted, std_ED's clusters)": f"{self.chance.accuracy_mean:.1%} "
                f"(95th pct {self.chance.accuracy_95:.1%})",
            }
            for m, c in self.correct.items()
        ]


def geometries(space: PCASpace, faces: np.ndarray) -> dict[str, np.ndarray]:
    """Each metric's coordinates of ``faces`` (n, S): Euclidean distance there is the metric
    (CD: monotone in it)."""
    beta = space.transform(faces)
    norm = np.linalg.norm(faces, axis=1, keepdims=True)
    return {
        "pca_ed": beta,
        "std_ed": beta / np.sqrt(space.variances),
        "cd": faces / np.where(norm > 0, norm, 1.0),
    }


def cluster(
    space: PCASpace, faces: np.ndarray, labels: np.ndarray, reading: str, *, seed: int
) -> Clustering:
    """Spherical GMM clusters of ``faces`` in each geometry, scored against ``labels``."""
    from sklearn.mixture import GaussianMixture

    k = len(np.unique(labels))
    correct, predicted = {}, {}
    for m, x in geometries(space, np.asarray(faces, dtype=np.float64)).items():
        gmm = GaussianMixture(k, covariance_type="spherical", n_init=10, random_state=seed)
        predicted[m] = gmm.fit(x).predict(x)
        correct[m] = matched_correct(labels, predicted[m])
    chance = permutation_chance(
        labels, predicted["std_ed"], np.random.default_rng(seed), permutations=100
    )
    return Clustering(reading, correct, chance)


def clustering_table(readings: list[Clustering]) -> pd.DataFrame:
    return pd.DataFrame([row for c in readings for row in c.rows()])


def clustering_finding(readings: list[Clustering]) -> Finding:
    """std_ED's matched accuracy below ED(β)'s and CD(α)'s (paired per sample), in each of the
    two readings; a verdict that changes between them is inconclusive."""
    if len(readings) != 2:
        raise ValueError(f"the finding reads two sets of samples; got {len(readings)}")
    evidence = [
        Evidence(Direction(-1), (c.correct["std_ed"], c.correct[other]))
        for c in readings
        for other in ("pca_ed", "cd")
    ]
    said = "; ".join(
        f"{c.reading}: "
        + ", ".join(f"{GEOMETRIES[m]} {v.mean():.0%}" for m, v in c.correct.items())
        + f" (chance {c.chance.accuracy_mean:.0%})"
        for c in readings
    )
    first = readings[0].correct
    return judged(
        "Section IV-B2",
        "std_ED(β) is unsuitable for clustering within a distribution",
        "stated (its acute sensitivity to some components), no numbers",
        f"matched accuracy of spherical-GMM clusters — {said}",
        evidence,
        "ci, paired per sample (the same faces clustered in each metric's geometry): matched "
        "accuracy std_ED − ED(β) < 0 and std_ED − CD(α) < 0 (SESOI 0.2 SD); per reading parts "
        "joined (rule join); readings (Table I's faces, the four emotions) disagreeing → "
        "inconclusive",
        note="chance: std_ED's clusters with the labels permuted; "
        + "; ".join(f"{c.reading}: {c.chance.text()}" for c in readings),
        parts=partial(readings_parts_verdict, first=2),
        value=float(first["std_ed"].mean() - first["pca_ed"].mean()),
        value_label="matched accuracy std_ED − ED(β), first reading",
        fitted="GMM in each geometry (and the std_ED metric's training), fitted per seed",
    )


def std_readings(
    space: PCASpace, table_i: list[np.ndarray], emotions: list[np.ndarray], *, seed: int
) -> list[Clustering]:
    """The two readings: Table I's final faces (one array per target) and the four emotions'
    (one per emotion)."""
    out = []
    for name, groups in (("Table I's faces", table_i), ("the four emotions", emotions)):
        x = np.concatenate(groups)
        y = np.repeat(np.arange(len(groups)), [len(g) for g in groups])
        out.append(cluster(space, x, y, name, seed=seed))
    return out
