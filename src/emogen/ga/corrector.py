"""What corrects the faces an engine shows: a callable, and the one made from a face model.

The engine takes its corrector as an argument (the GA does not import the correction code);
:func:`correctives_of` makes one from a model, with the numbered eq. 5 collision solver
(:mod:`emogen.solvers`) the engine's state records.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from emogen.ga.genome import DynamicGenome, Genome
from emogen.ga.motion import correct_keyframes
from emogen.ga.population import Population, readonly

#: Corrects a batch of full weight vectors before they are shown: returns
#: (corrective names, (n_faces, C) corrective weights). ``correctives_of(model)`` makes one.
Corrector = Callable[[np.ndarray], tuple[tuple[str, ...], np.ndarray]]


class ModelCorrector:
    """A corrector from a face model: :func:`emogen.correct.correct_faces` (combinational +
    collision correctives) with eq. 5 block solver ``solver`` (recorded in the engine's state
    as ``collision_solver``, so that a recorded run is corrected again as it was)."""

    def __init__(self, model: Any, solver: int | None = None) -> None:
        from emogen.solvers import CURRENT_SOLVER, check_solver

        self.model = model
        self.solver = check_solver(CURRENT_SOLVER if solver is None else solver)

    def __call__(self, weights: np.ndarray) -> tuple[tuple[str, ...], np.ndarray]:
        from emogen.correct.faces import correct_faces

        result = correct_faces(self.model, weights, solver=self.solver)
        return tuple(result.corrective_names), np.asarray(result.correctives, dtype=np.float64)


def correctives_of(model: Any, solver: int | None = None) -> Corrector:
    """A :class:`ModelCorrector` of ``model`` (``solver``: default the current one)."""
    return ModelCorrector(model, solver)


def corrected(
    population: Population,
    corrector: Corrector,
    genome: Genome,
    expand: Callable[[np.ndarray], np.ndarray],
) -> Population:
    """``population`` with its corrective weights; a dynamic one's also at its keyframes
    (:func:`emogen.ga.motion.correct_keyframes`; ``expand``: genes to full weight vectors)."""
    names, values = corrector(population.weights)
    keyed = None
    if isinstance(genome, DynamicGenome):
        keyed = readonly(correct_keyframes(genome, population.genes, expand, corrector)[1])
    return replace(
        population,
        correctives=readonly(np.asarray(values)),
        corrective_names=tuple(names),
        keyframe_correctives=keyed,
    )
