"""Correcting a model's faces: the entry points (paper Section III-A).

The model layer knows nothing of correctives; these functions take the model as an argument:

* :func:`correct_faces` — weights (n_faces, n_shapes) → :class:`CorrectionResult`;
* :func:`corrected_vertices` — the vertices of a correction;
* :func:`evaluate_corrected` — both in one call (``FaceModel.evaluate`` plus the correctives);
* :func:`model_correctives` — the model's :class:`Correctives` bundle;
* :func:`corrector_for` — the model's :class:`Corrector`, built once per model object.
"""

from __future__ import annotations

import threading
import weakref
from typing import TYPE_CHECKING

import numpy as np

from emogen.correct.apply import CorrectionResult, Corrector
from emogen.correct.solve import CURRENT_SOLVER
from emogen.errors import ShapeError

if TYPE_CHECKING:
    from emogen.correct.correctives import Correctives
    from emogen.model.face import FaceModel

__all__ = [
    "correct_faces",
    "corrected_vertices",
    "corrector_for",
    "evaluate_corrected",
    "model_correctives",
]

# One Corrector per model object (a model with another identity is another object). Weak keys:
# the corrector is dropped with its model; the Corrector keeps no reference to the model.
_CORRECTORS: weakref.WeakKeyDictionary[FaceModel, Corrector] = weakref.WeakKeyDictionary()
_LOCK = threading.Lock()


def corrector_for(model: FaceModel) -> Corrector:
    """The :class:`Corrector` of ``model`` (its correctives built or read from the cache once)."""
    with _LOCK:
        found = _CORRECTORS.get(model)
    if found is None:
        found = Corrector(model)
        with _LOCK:
            found = _CORRECTORS.setdefault(model, found)
    return found


def model_correctives(model: FaceModel) -> Correctives:
    """The model's corrective shapes (built from its geometry once, cached on disk)."""
    return corrector_for(model).correctives


def correct_faces(
    model: FaceModel, weights: np.ndarray, *, collisions: bool = True, solver: int = CURRENT_SOLVER
) -> CorrectionResult:
    """Correct faces of ``model``: weights (n_faces, n_shapes) in [0, 1] → the correction.

    Companion shapes are capped at their leads (``mouthClose`` ≤ ``jawOpen``), the
    combinational correctives take the product of their drivers' weights, and the eight
    collision correctives are solved (eq. 5) until no lip or teeth collision remains. The
    result keeps the core weights, the effective weights and every corrective weight
    separately, and says what remains uncorrected. A face without collision gets collision
    weights of exactly zero. ``solver``: the eq. 5 block solver
    (:data:`emogen.correct.solve.SOLVERS`; a recorded study trial says which it used).
    """
    w = model.check_weights(weights, np.float64)
    if np.any((w < 0) | (w > 1)):
        raise ShapeError("weights must lie in [0, 1] to be corrected")
    return corrector_for(model).correct(w, collisions=collisions, solver=solver)


def corrected_vertices(
    model: FaceModel,
    result: CorrectionResult,
    *,
    gaze: bool = True,
    out: np.ndarray | None = None,
    chunk: int | None = None,
) -> np.ndarray:
    """Vertices of corrected faces (from :func:`correct_faces`): (n_faces, n_vertices, 3) float32.

    The effective shape weights are blended as by ``FaceModel.evaluate``, then the correctives'
    offsets are added to the faces that have any (the others stay bit-identical).
    """
    kwargs = {} if chunk is None else {"chunk": chunk}
    vertices = model.evaluate(result.weights, gaze=gaze, out=out, **kwargs)
    corrector_for(model).add_offsets(result, vertices)
    return vertices


def evaluate_corrected(
    model: FaceModel,
    weights: np.ndarray,
    *,
    gaze: bool = True,
    out: np.ndarray | None = None,
    chunk: int | None = None,
) -> np.ndarray:
    """Vertices of the corrected faces: weights (n_faces, n_shapes) → (n_faces, V, 3) float32.

    :func:`correct_faces` then :func:`corrected_vertices`; a face none of the correctives
    touches is bit-identical to ``model.evaluate(weights)``.
    """
    result = correct_faces(model, weights)
    return corrected_vertices(model, result, gaze=gaze, out=out, chunk=chunk)
