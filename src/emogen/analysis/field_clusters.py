"""Clusters of participants by their perceptive fields — or the answer that there are none.

Distance between two participants' fields of an emotion: the L2 distance between the fields
normalised to unit L2 norm, d² = 2 − 2·overlap (overlap: :func:`emogen.analysis.fields.
overlap_matrix`), a metric; over several emotions, d² averaged over them. Participants are
clustered by spectral clustering of the affinity 1 − d²/2 (the mean overlap; Ng, Jordan & Weiss
2002) into k = 2 … ``max_k`` clusters, and k is the one with the largest mean silhouette on d
(Rousseeuw 1987).

A silhouette is positive on any data, structured or not, so the clusters are reported only
when the best silhouette beats a **null of one population** (in the spirit of SigClust: Liu,
Hayes, Nobel & Marron 2008, *JASA* 103:1281): the participants' field centres (their mean face
per emotion, all emotions jointly) are redrawn from one multivariate Gaussian with the observed
mean and covariance of the centres, each participant's faces keep their own scatter about
their centre, and the whole procedure (overlaps, clustering, best silhouette) is repeated on
``n_null`` such studies. p = (1 + #null ≥ observed) / (1 + n_null); "structure" when p < α,
otherwise "no structure" and no clusters are reported. The null keeps everything but
multimodality: the spread of the participants, their own variability, the bandwidth.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from emogen.analysis.fields import Fields, overlap_matrix
from emogen.errors import ConfigError, DataError


@dataclass(frozen=True)
class Clustering:
    """The participants clustered (``labels``, 1…k) with the best silhouette over k, the
    silhouette of every k tried, and the one-population test of that best silhouette."""

    participants: tuple[str, ...]
    emotions: tuple[str, ...]
    k: int
    labels: np.ndarray
    silhouettes: dict[int, float]
    silhouette: float
    p_value: float
    n_null: int
    alpha: float

    @property
    def structure(self) -> bool:
        return self.p_value < self.alpha

    def table(self) -> pd.DataFrame:
        """One row per participant: the cluster (0 for everyone when there is no structure)."""
        return pd.DataFrame(
            {
                "participant_id": list(self.participants),
                "cluster": self.labels if self.structure else np.zeros(len(self.labels), int),
            }
        )


def complete_participants(fields: Fields, emotions: tuple[str, ...]) -> list[str]:
    """Participants with a field of every one of ``emotions``."""
    sets = [set(fields.participants(e)) for e in emotions]
    return sorted(set.intersection(*sets)) if sets else []


def field_distances(points: dict[str, list[np.ndarray]], bandwidth: dict[str, float]) -> np.ndarray:
    """(n, n) distances of participants' fields, d² = 2 − 2·overlap averaged over emotions;
    ``points[emotion]`` lists every participant's faces of that emotion in one order."""
    d2 = np.zeros((len(next(iter(points.values()))),) * 2)
    for e, pts in points.items():
        d2 += 2.0 - 2.0 * overlap_matrix(pts, pts, bandwidth[e])
    d2 /= len(points)
    np.fill_diagonal(d2, 0.0)
    return np.sqrt(np.clip(d2, 0.0, None))


def best_clusters(dist: np.ndarray, max_k: int) -> tuple[int, np.ndarray, dict[int, float]]:
    """Spectral clusters of the affinity 1 − d²/2 (the mean overlap) for k = 2…max_k: (best k
    by mean silhouette on ``dist``, its labels 1…k, the silhouette of each k). One spectral
    embedding of ``max_k`` dimensions serves every k (its first k eigenvectors are the
    k-cluster embedding), the labels by :func:`cluster_qr` — the embedding is most of the
    cost, and the GA studies' null repeats it ``n_null`` times (docs/analysis.md, speed)."""
    from sklearn.metrics import silhouette_score

    affinity = np.clip(1.0 - dist**2 / 2.0, 0.0, 1.0)
    maps = spectral_maps(affinity, max_k)
    sil, labels = {}, {}
    for k in range(2, max_k + 1):
        lab = cluster_qr(maps[:, :k]) + 1
        if len(np.unique(lab)) < 2:
            continue
        labels[k] = lab
        sil[k] = float(silhouette_score(dist, lab, metric="precomputed"))
    if not sil:
        return 1, np.ones(len(dist), dtype=int), {}
    best = max(sil, key=lambda k: sil[k])
    return best, labels[best], sil


def spectral_maps(affinity: np.ndarray, k: int) -> np.ndarray:
    """(n, k) spectral embedding of a dense affinity matrix (Ng, Jordan & Weiss 2002): the
    eigenvectors of the k smallest eigenvalues of the normalised graph Laplacian, divided by
    the square roots of the degrees, each signed so that its largest entry is positive — as
    scikit-learn's ``spectral_embedding(drop_first=False)``, but by a dense symmetric
    eigensolver: the matrix is participants × participants (336 × 336), where ARPACK's
    shift-invert (an LU per call) cost more than the whole dense solution."""
    from scipy.linalg import eigh
    from scipy.sparse.csgraph import laplacian

    lap, degree_root = laplacian(affinity, normed=True, return_diag=True)
    np.fill_diagonal(lap, 1.0)  # the self-affinity does not count, as in scikit-learn
    _values, vectors = eigh(lap, subset_by_index=[0, k - 1])
    maps = vectors / degree_root[:, None]
    largest = np.abs(maps).argmax(axis=0)
    return np.asarray(maps * np.sign(maps[largest, np.arange(k)]))


def cluster_qr(maps: np.ndarray) -> np.ndarray:
    """Labels 0…k−1 of the rows of a spectral embedding ``maps`` (n, k) by column-pivoted QR
    (Damle, Minden & Ying 2019, *Inf. Inference* 8:181): the pivots pick k rows that span the
    embedding, the polar factor of those rows rotates the embedding toward the axes, and each
    row joins the axis it is largest on."""
    from scipy.linalg import qr, svd

    k = maps.shape[1]
    _q, _r, pivots = qr(maps.T, pivoting=True)
    left, _s, right = svd(maps[pivots[:k]].T)
    return np.asarray(np.abs(maps @ (left @ right)).argmax(axis=1))


def _null_studies(
    points: dict[str, list[np.ndarray]], rng: np.random.Generator
) -> dict[str, list[np.ndarray]]:
    """One study of the one-population null: centres redrawn from N(mean, cov of centres),
    jointly over emotions, each participant's scatter about their centre kept."""
    emotions = list(points)
    n = len(points[emotions[0]])
    centres = np.hstack([np.stack([x.mean(axis=0) for x in points[e]]) for e in emotions])
    centred = centres - centres.mean(axis=0)
    drawn = centres.mean(axis=0) + rng.standard_normal((n, n)) @ centred / np.sqrt(n - 1)
    out, col = {}, 0
    for e in emotions:
        k = points[e][0].shape[1]
        out[e] = [x - x.mean(axis=0) + drawn[i, col : col + k] for i, x in enumerate(points[e])]
        col += k
    return out


def cluster_fields(
    fields: Fields,
    emotions: tuple[str, ...] | None = None,
    *,
    rng: np.random.Generator,
    alpha: float = 0.05,
    n_null: int = 99,
    max_k: int = 6,
) -> Clustering:
    """Cluster the participants with a field of every one of ``emotions`` (default: all) by
    their fields, and test the best silhouette against the one-population null."""
    if 1.0 / (1 + n_null) >= alpha:
        raise ConfigError(
            f"{n_null} null studies cannot give p < α = {alpha}: use at least "
            f"{int(np.ceil(1 / alpha))} of them"
        )
    emotions = tuple(emotions or fields.emotions)
    who = complete_participants(fields, emotions)
    if len(who) < 6:
        raise DataError(
            f"clustering needs at least 6 participants with fields of {', '.join(emotions)}; "
            f"{len(who)} have them"
        )
    max_k = max(2, min(max_k, len(who) // 3))
    points = {e: [fields.points[(p, e)] for p in who] for e in emotions}
    k, labels, sil = best_clusters(field_distances(points, fields.bandwidth), max_k)
    observed = max(sil.values()) if sil else 0.0
    null = np.empty(n_null)
    for b in range(n_null):
        fake = _null_studies(points, rng)
        _, _, s = best_clusters(field_distances(fake, fields.bandwidth), max_k)
        null[b] = max(s.values()) if s else 0.0
    p = float((1 + np.sum(null >= observed)) / (1 + n_null))
    return Clustering(tuple(who), emotions, k, labels, sil, observed, p, n_null, alpha)
