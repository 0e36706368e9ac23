"""Similarity metrics between faces, batched (Section IV-B)."""

from __future__ import annotations

import numpy as np

from emogen.errors import ShapeError


def cosine_distance(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cosine distance CD = 1 − a·b / (‖a‖ ‖b‖) (eq. 12), row by row.

    a : (n_faces, n) or (n,) float; b : (n_faces, n) or (n,) float, broadcast against ``a``.
    Returns (n_faces,) float in [0, 2] (a 1-D pair gives a 0-d array).

    Eq. 12 is undefined for a zero vector (the neutral face). We define CD = 1.0 (no
    compositional similarity, as for orthogonal faces) when exactly one side is zero, and 0.0
    when both are zero (identical faces).
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if a.shape[-1] != b.shape[-1]:
        raise ShapeError(
            f"cosine_distance needs vectors of equal length; got {a.shape} and {b.shape}"
        )
    na = np.linalg.norm(a, axis=-1)
    nb = np.linalg.norm(b, axis=-1)
    dot = (a * b).sum(-1)
    denom = na * nb
    with np.errstate(invalid="ignore", divide="ignore"):
        cd = 1.0 - dot / denom
    zero_a, zero_b = na == 0, nb == 0
    cd = np.where(zero_a | zero_b, np.where(zero_a & zero_b, 0.0, 1.0), cd)
    return np.clip(cd, 0.0, 2.0)
