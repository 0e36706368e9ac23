"""Similarity metrics between faces, batched (Section IV-B).

Theoretical: ED on unique core genes (eq. 11), CD on full weight vectors (eq. 12), vertex RMS
(eq. 13). Empirical, fitted on a training set: ED and standardised ED in PCA space (eqs. 14–15),
Mahalanobis distance on vertex offsets (eq. 16). Dynamic faces (:mod:`emogen.metrics.dynamic`):
CD over the time-sampled trajectory, and a timing distance. Every function compares faces row by row:
``(n_faces, n)`` against ``(n_faces, n)`` or against one ``(n,)`` target.
"""

from emogen.metrics.basic import cosine_distance, euclidean_distance, gene_euclidean_distance
from emogen.metrics.dynamic import timing_distance, trajectory_cd
from emogen.metrics.empirical import PCASpace, VertexMahalanobis, fit_pca
from emogen.metrics.vertex import VertexRMS, vertex_rms

__all__ = [
    "PCASpace",
    "VertexMahalanobis",
    "VertexRMS",
    "cosine_distance",
    "euclidean_distance",
    "fit_pca",
    "gene_euclidean_distance",
    "timing_distance",
    "trajectory_cd",
    "vertex_rms",
]
