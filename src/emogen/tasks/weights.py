"""What a shown face's stored weights are: the model's shapes, then its correctives, if any."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from emogen.ga.engine import Population
from emogen.model.rig import Rig

Floats = npt.NDArray[np.float64]


def _correctives(population: Population) -> tuple[list[str], Floats] | None:
    """Corrective columns a population carries, if the engine corrects faces.

    Either ``population.correction`` (an ``emogen.correct`` CorrectionResult: combinational then
    collision weights) or ``population.correctives`` (n_faces, C) with ``corrective_names``.
    """
    correction = getattr(population, "correction", None)
    if correction is not None:
        names = [*correction.combinational_names, *correction.collision_names]
        values = np.hstack([correction.combinational, correction.collision])
        return names, np.asarray(values, dtype=np.float64).reshape(len(population), -1)
    extra = getattr(population, "correctives", None)
    if extra is None:
        return None
    values = np.asarray(extra, dtype=np.float64).reshape(len(population), -1)
    given = getattr(population, "corrective_names", None)
    names = (
        list(given) if given is not None else [f"corrective_{i}" for i in range(values.shape[1])]
    )
    return names, values


def full_weights(population: Population) -> Floats:
    """(n_faces, n_columns) float: the population's full weights, then its correctives if any."""
    w = np.asarray(population.weights, dtype=np.float64)
    extra = _correctives(population)
    return w if extra is None else np.hstack([w, extra[1]])


def weight_names(population: Population, rig: Rig) -> list[str]:
    """Column names of :func:`full_weights`: the model's shapes, then the correctives."""
    extra = _correctives(population)
    return list(rig.shape_names) + ([] if extra is None else extra[0])
