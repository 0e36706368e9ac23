"""The theoretical metrics on weight vectors: ED (eq. 11) and CD (eq. 12), batched.

Both work row by row with numpy broadcasting: ``a : (n_faces, n)`` against ``b : (n_faces, n)``
or ``(n,)`` (one target for every face). Which vectors to pass is part of the metric's
definition (Section IV-B1):

* **ED** compares *unique core* gene vectors α′ (a left/right pair once, no correctives, no
  disabled shapes) — :func:`gene_euclidean_distance` contracts full weights with the rig.
* **CD** compares *full* weight vectors α (every shape, correctives included).
"""

from __future__ import annotations

import numpy as np

from emogen.errors import ShapeError
from emogen.model.rig import Rig


def _pair(a: np.ndarray, b: np.ndarray, name: str) -> tuple[np.ndarray, np.ndarray]:
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if a.shape[-1] != b.shape[-1]:
        raise ShapeError(f"{name} needs vectors of equal length; got {a.shape} and {b.shape}")
    return a, b


def euclidean_distance(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """ED = ‖a − b‖ (eq. 11), row by row.

    a, b : (n_faces, n) or (n,) float, broadcast. Returns (n_faces,) float >= 0.
    """
    a, b = _pair(a, b, "euclidean_distance")
    return np.sqrt(((a - b) ** 2).sum(-1))


def gene_euclidean_distance(
    rig: Rig, a: np.ndarray, b: np.ndarray, *, eye_motion: bool = True
) -> np.ndarray:
    """ED(α′₁, α′₂) (eq. 11) between full weight vectors, on their unique core genes.

    a, b : (n_faces, n_shapes) or (n_shapes,) full weights; each is contracted to the rig's
    active genes (a pair's value is the mean of its shapes, exact for symmetric faces; eye genes
    only with ``eye_motion``; correctives and excluded shapes are not genes). Returns (n_faces,).
    """
    a2 = np.atleast_2d(np.asarray(a, dtype=np.float64))
    b2 = np.atleast_2d(np.asarray(b, dtype=np.float64))
    d = euclidean_distance(rig.contract(a2, eye_motion), rig.contract(b2, eye_motion))
    return d[0] if np.ndim(a) == 1 and np.ndim(b) == 1 else d


def cosine_distance(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cosine distance CD = 1 − a·b / (‖a‖ ‖b‖) (eq. 12), row by row.

    a : (n_faces, n) or (n,) float; b : (n_faces, n) or (n,) float, broadcast against ``a``.
    Returns (n_faces,) float in [0, 2] (a 1-D pair gives a 0-d array).

    Eq. 12 is undefined for a zero vector (the neutral face). We define CD = 1.0 (no
    compositional similarity, as for orthogonal faces) when exactly one side is zero, and 0.0
    when both are zero (identical faces). Rounding can push 1 − cos a hair outside [0, 2]; the
    result is clipped to that range.
    """
    a, b = _pair(a, b, "cosine_distance")
    na = np.linalg.norm(a, axis=-1)
    nb = np.linalg.norm(b, axis=-1)
    dot = (a * b).sum(-1)
    denom = na * nb
    with np.errstate(invalid="ignore", divide="ignore"):
        cd = 1.0 - dot / denom
    zero_a, zero_b = na == 0, nb == 0
    cd = np.where(zero_a | zero_b, np.where(zero_a & zero_b, 0.0, 1.0), cd)
    return np.clip(cd, 0.0, 2.0)
