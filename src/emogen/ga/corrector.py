"""What corrects the faces an engine shows: a callable, and the one made from a face model.

The engine takes its corrector as an argument (the GA does not import the correction code);
:func:`correctives_of` makes one from a model, with the numbered eq. 5 collision solver
(:mod:`emogen.solvers`) the engine's state records.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import replace
from typing import Any

import numpy as np

from emogen.ga.genome import DynamicGenome, Genome
from emogen.ga.motion import correct_keyframes
from emogen.ga.population import Population, readonly

#: Corrects a batch of full weight vectors before they are shown: returns
#: (corrective names, (n_faces, C) corrective weights). ``correctives_of(model)`` makes one.
Corrector = Callable[[np.ndarray], tuple[tuple[str, ...], np.ndarray]]


#: Corrections made ahead that a corrector keeps until the same weights come again (a step's
#: next generation, made before its write transaction: :func:`corrected_ahead`); the oldest
#: goes first. Two batches a step (the faces, a dynamic population's keyframes), so 64 hold the
#: steps of 32 requests in flight at once; one evicted costs only its correction made again.
AHEAD_KEPT = 64

_ahead = threading.local()


@contextmanager
def corrected_ahead() -> Iterator[None]:
    """In this block (this thread), a :class:`ModelCorrector` keeps what it corrects, each
    batch for one later call with the same weights, bit for bit, in any thread — the study's
    steps make a selection's next generation before the write transaction
    (``Task.ahead``), so that the write transaction, which makes it again, finds its
    correction made (docs/study.md, "Corrected ahead")."""
    _ahead.on = True
    try:
        yield
    finally:
        _ahead.on = False


class ModelCorrector:
    """A corrector from a face model: :func:`emogen.correct.correct_faces` (combinational +
    collision correctives) with eq. 5 block solver ``solver`` (recorded in the engine's state
    as ``collision_solver``, so that a recorded run is corrected again as it was).

    A batch corrected under :func:`corrected_ahead` is kept (at most :data:`AHEAD_KEPT`) and
    answered once, without correcting it again, to the next call with the same weights (equal
    bytes): the correction is a function of the weights alone, so the answer is the same."""

    def __init__(self, model: Any, solver: int | None = None) -> None:
        from emogen.solvers import CURRENT_SOLVER, check_solver

        self.model = model
        self.solver = check_solver(CURRENT_SOLVER if solver is None else solver)
        self._kept: OrderedDict[bytes, tuple[tuple[str, ...], np.ndarray]] = OrderedDict()
        self._lock = threading.Lock()

    def __call__(self, weights: np.ndarray) -> tuple[tuple[str, ...], np.ndarray]:
        from emogen.correct.faces import correct_faces

        w = np.ascontiguousarray(weights, dtype=np.float64)
        key = repr(w.shape).encode() + w.tobytes()
        ahead = getattr(_ahead, "on", False)
        if not ahead:
            with self._lock:
                kept = self._kept.pop(key, None)
            if kept is not None:
                return kept[0], kept[1].copy()
        result = correct_faces(self.model, w, solver=self.solver)
        out = tuple(result.corrective_names), np.asarray(result.correctives, dtype=np.float64)
        if ahead:
            with self._lock:
                self._kept[key] = (out[0], out[1].copy())
                while len(self._kept) > AHEAD_KEPT:
                    self._kept.popitem(last=False)
        return out


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
