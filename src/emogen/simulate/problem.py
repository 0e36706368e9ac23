"""What a simulation needs and what it produces: the problem, the corrections, the run arrays.

A :class:`Problem` is everything needed to simulate runs of one configuration (picklable, for
workers); :class:`RunArrays` is what R runs showed and chose, generation by generation. The
runs themselves are advanced by :mod:`emogen.simulate.vectorised`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from emogen.config import SimulationConfig
from emogen.correct.faces import correct_faces, model_correctives
from emogen.errors import ConfigError
from emogen.ga.genome import STATIC, Genome
from emogen.model.rig import Rig
from emogen.simulate.dynamic import DynamicView, HeldTiming
from emogen.simulate.observer import Metric

if TYPE_CHECKING:
    from emogen.model.face import FaceModel


@dataclass(frozen=True, eq=False)
class Correction:
    """The model's corrections applied to every shown face (:func:`emogen.correct.correct_faces`).

    ``correction(weights (B, S))`` → the corrected full weight vectors (B, S + C): the
    effective shape weights (companions capped), then every corrective weight (combinational
    products, collision weights of eq. 5) in ``names[S:]`` order. The corrected face is the
    blend of those weights (gaze on the shapes), so the metrics see exactly what a participant
    sees. Identical faces of a batch are corrected once. The GA keeps evolving the uncorrected
    genes, as with a participant, who only ever sees corrected faces.
    """

    model: FaceModel

    @property
    def names(self) -> tuple[str, ...]:
        """Column names of the corrected vectors: the shapes, then the correctives."""
        return tuple(self.model.shape_names) + tuple(model_correctives(self.model).names)

    @property
    def deltas(self) -> np.ndarray:
        """(C, V, 3) the correctives' vertex offsets, in ``names[S:]`` order."""
        c = model_correctives(self.model)
        return np.concatenate([c.combinational_deltas, c.collision_deltas])

    def __call__(self, weights: np.ndarray) -> np.ndarray:
        w = np.asarray(weights, dtype=np.float64)
        unique, inverse = np.unique(w, axis=0, return_inverse=True)
        result = correct_faces(self.model, unique)
        corrected = np.concatenate([result.weights, result.correctives], axis=1)
        return np.asarray(corrected[inverse.reshape(-1)], dtype=np.float64)


def make_correction(model: FaceModel | None) -> Correction:
    """The corrections for ``correct = true`` (they need the face model, not only its rig)."""
    if model is None:
        raise ConfigError("correct = true needs the face model, not only its rig")
    from emogen.model.face import FaceModel

    if not isinstance(model, FaceModel):
        raise ConfigError(
            "correct = true needs a FaceModel (its geometry gives the correctives, "
            f"emogen.correct); got {type(model).__name__}"
        )
    return Correction(model)


@dataclass(frozen=True, eq=False)
class Problem:
    """Everything needed to simulate runs of one configuration (picklable, for workers).

    target : the target's shown full weights, (n_shapes,) or, corrected, (n_shapes + C,) —
    see :attr:`columns`; fixed_sets : (n_sets, N, K) for fixed initialisation.
    """

    config: SimulationConfig
    rig: Rig
    target: np.ndarray
    metric: Metric
    fixed_sets: np.ndarray | None = None
    correction: Correction | None = None
    all_weights: bool = False
    target_source: dict[str, Any] = field(default_factory=dict)
    #: Dynamic faces: the target that moves and the three distances (None: static faces).
    dynamic: DynamicView | None = None

    @property
    def genome(self) -> Genome:
        """What a gene is: static, dynamic, or dynamic with the target's timing held."""
        if self.dynamic is None:
            return STATIC
        settings = self.config.dynamic
        if settings is not None and settings.hold_timing:
            return HeldTiming(self.dynamic.genome, self.dynamic.target[:, 1:])
        return self.dynamic.genome

    @property
    def n_generations(self) -> int:
        """Generations shown: G + 1."""
        return self.config.ga.generations + 1

    @property
    def columns(self) -> tuple[str, ...]:
        """Names of the shown full weight vectors' columns (shapes, then any correctives)."""
        return self.rig.shape_names if self.correction is None else self.correction.names


@dataclass(frozen=True)
class RunArrays:
    """What R runs showed and chose, generation by generation.

    runs, seeds : (R,) int; distance : (R, G+1, N) the selection metric to the target; error :
    (R, G+1, N) CD to the target (the paper's convergence measure; dynamic faces: over the
    trajectory); peak_error, timing_error : (R, G+1, N) a dynamic face's peak CD and timing
    distance (s), None for static faces; rank : (R, G+1, N) int,
    0 for the elite, 1… for the other selections in choice order, −1 unselected; operators :
    (R, G+1, N) str; weights : (R, G+1, N, S) shown full weights, or None; fixed_options : (R,)
    the fixed set used (−1 for protocol initialisation).
    """

    runs: np.ndarray
    seeds: np.ndarray
    distance: np.ndarray
    error: np.ndarray
    rank: np.ndarray
    operators: np.ndarray
    weights: np.ndarray | None
    fixed_options: np.ndarray
    peak_error: np.ndarray | None = None
    timing_error: np.ndarray | None = None

    @staticmethod
    def concatenate(parts: list[RunArrays]) -> RunArrays:
        """Parts of one simulation, in run order (one part is returned as it is, uncopied)."""
        if len(parts) == 1:
            return parts[0]
        parts = sorted(parts, key=lambda p: int(p.runs[0]) if len(p.runs) else 0)

        def cat(name: str) -> np.ndarray:
            return np.concatenate([getattr(p, name) for p in parts])

        def maybe(name: str) -> np.ndarray | None:
            values = [getattr(p, name) for p in parts]
            return None if any(v is None for v in values) else np.concatenate(values)

        return RunArrays(
            runs=cat("runs"),
            seeds=cat("seeds"),
            distance=cat("distance"),
            error=cat("error"),
            rank=cat("rank"),
            operators=cat("operators"),
            weights=maybe("weights"),
            fixed_options=cat("fixed_options"),
            peak_error=maybe("peak_error"),
            timing_error=maybe("timing_error"),
        )
