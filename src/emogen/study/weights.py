"""What a shown face's stored weights are: the model's shapes, then its correctives, if any.

Also the per-identity correctors a study's engines use (:class:`StudyCorrectors`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from emogen.errors import ConfigError
from emogen.ga.engine import Corrector, Population, correctives_of
from emogen.model.rig import Rig
from emogen.study.config import StudyConfig

if TYPE_CHECKING:
    from emogen.model.face import FaceModel

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


class StudyCorrectors:
    """One corrector per identity shape and collision solver (``correctives_of`` the model with
    the shape of the study's identity of that name; identities that share a shape share it),
    made on first use; none when the study does not correct faces. ``solver``: the eq. 5 block solver a trial was
    recorded with (:func:`emogen.ga.state.collision_solver_of_state`; default the current)."""

    def __init__(self, config: StudyConfig, model: FaceModel | None) -> None:
        if config.correct and model is None:
            raise ConfigError(
                "the study corrects faces (correct = true): the server needs the face model "
                "(pass model=…), or set correct = false"
            )
        self.config = config
        self.model = model if config.correct else None
        self._models: dict[str | tuple[float, ...], FaceModel] = {}
        self._made: dict[tuple[str | tuple[float, ...], int], Corrector] = {}

    def __call__(self, identity: str, solver: int | None = None) -> Corrector | None:
        if self.model is None:
            return None
        if solver is None:
            from emogen.solvers import CURRENT_SOLVER

            solver = CURRENT_SOLVER
        shape = self.config.identity_of(identity).shape
        if (shape, solver) not in self._made:
            if shape not in self._models:
                self._models[shape] = (
                    self.model if shape == "generic" else self.model.with_identity(shape)
                )
            self._made[(shape, solver)] = correctives_of(self._models[shape], solver)
        return self._made[(shape, solver)]
