"""Simulated observers: they select faces as a participant would, by a similarity metric."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from emogen.errors import ShapeError
from emogen.ga.engine import Population
from emogen.metrics import cosine_distance


def rank_by_cosine(weights: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Faces ordered by cosine distance to the target, closest first (ties: slot order).

    weights : (n_faces, n_shapes) float, full weight vectors; target : (n_shapes,) float.
    Returns (order (n_faces,) int, distances (n_faces,) float in slot order).
    """
    weights = np.asarray(weights, dtype=np.float64)
    target = np.asarray(target, dtype=np.float64)
    if weights.ndim != 2 or target.shape != (weights.shape[1],):
        raise ShapeError(
            f"weights (n_faces, n_shapes) and target (n_shapes,) must agree; got "
            f"{weights.shape} and {target.shape}"
        )
    distances = cosine_distance(weights, target[None, :])
    return np.argsort(distances, kind="stable"), distances


class CosineObserver:
    """Selects the faces closest to a target by CD (eq. 12) on full weight vectors.

    ``count(g)`` is how many faces it selects in generation g (the elite and the next-best
    ``count(g) − 1`` as the others). In the last generation (``final``) only the elite
    counts, as in the paper's simulations. With ``ranking=True`` (the classical variant) it
    ranks the whole population instead: the elite, then every other face best first.
    """

    def __init__(
        self,
        target: np.ndarray,
        count: Callable[[int], int],
        *,
        final: int,
        ranking: bool = False,
    ) -> None:
        self.target = np.asarray(target, dtype=np.float64)
        self.count = count
        self.final = final
        self.ranking = ranking

    def choose(self, population: Population) -> tuple[int, list[int], float]:
        """(elite id, other ids best first, the elite's CD to the target)."""
        order, distances = rank_by_cosine(population.weights, self.target)
        ids = population.ids[order]
        g = population.generation
        if g >= self.final:
            n = 1
        elif self.ranking:
            n = len(ids)
        else:
            n = min(self.count(g), len(ids))
        return int(ids[0]), [int(i) for i in ids[1:n]], float(distances[order[0]])
