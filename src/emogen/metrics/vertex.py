"""Vertex RMS (eq. 13): the root-mean-square distance between corresponding vertices.

:func:`vertex_rms` is eq. 13 on evaluated vertices. :class:`VertexRMS` gives the same number
from weight vectors without evaluating the mesh, using the model's linear structure.

For vertices that only blend, v(α) = B₀ + α D (D the (S, 3) deltas of each vertex), so

    Σ_n ‖v₁,ₙ − v₂,ₙ‖² = ‖(α₁ − α₂) D‖² = (α₁ − α₂) G (α₁ − α₂)ᵀ,   G = D Dᵀ  (S × S)

— exact, and O(S²) per pair instead of O(N·S). The one nonlinearity of the model is the gaze:
the eyeballs rotate rigidly with the ``eyeLook*`` weights (:meth:`FaceModel.evaluate`). So
:class:`VertexRMS` splits the vertices: the Gram matrix G covers every vertex except the two
eyeballs, and the eyeballs (3,140 of 26,719 vertices in ICT) get an exact closed form too
(their rigid rotation turns the squared distance into a bilinear form of [1, α₁] and [1, α₂]
weighted by the rotations; see :class:`VertexRMS`). The result equals eq. 13 on
``model.evaluate(weights)`` up to float rounding, for every face, and never evaluates a vertex.

It is exact for faces whose vertices the model computes from their weights alone. A
corrective step that moves vertices beyond what its corrected weights blend (a nonlinear
vertex-level correction) is not covered: there, evaluate the corrected vertices and use
:func:`vertex_rms` (the simulation runner does so when a model's correction says it is not
weight-linear).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from emogen.errors import ShapeError

if TYPE_CHECKING:
    from emogen.model.face import FaceModel


def vertex_rms(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """vrtx_rms(F₁, F₂) = sqrt(1/N Σ_n ‖v₁,ₙ − v₂,ₙ‖²) (eq. 13), face by face.

    a, b : (n_faces, N, 3) or (N, 3) vertices, broadcast. Returns (n_faces,) float.
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if a.shape[-2:] != b.shape[-2:] or a.shape[-1] != 3:
        raise ShapeError(
            f"vertex_rms needs vertex arrays (…, N, 3) of equal N; got {a.shape} and {b.shape}"
        )
    return np.sqrt(((a - b) ** 2).sum(-1).mean(-1))


class VertexRMS:
    """Eq. 13 between faces given by full weight vectors (see the module docstring).

    ``VertexRMS(model)`` precomputes, once, the Gram matrix of the non-eyeball deltas and, per
    eyeball, the second moments T of its pivot-relative neutral and deltas; it does not keep
    the model (it pickles small, for worker processes). ``gaze=False`` treats the eyeballs as
    blend-only, like ``model.evaluate(w, gaze=False)``. ``extra_deltas`` (C, N, 3): further
    shapes blended after the model's (the correctives of :func:`emogen.correct.evaluate_corrected`); the
    weights are then (…, S + C), the model's shapes first.

    **Eyeballs in closed form.** An eyeball vertex is p = x Rᵀ + c with x = (B₀ − c) + α D
    (row vectors) and R the gaze rotation of the face. For two faces,
    Σ_v ‖p₁ − p₂‖² = Σ_v ‖x₁‖² + ‖x₂‖² − 2 x₁ M x₂ᵀ with M = R₁ᵀ R₂, and with α̂ = [1, α],
    Σ_v x₁ᵢ x₂ⱼ = α̂₁ Tᵢⱼ α̂₂ᵀ, Tᵢⱼ = Σ_v X_{·vi} X_{·vj}ᵀ ((S+1) × (S+1), X = [B₀ − c; D]).
    So no vertex is ever evaluated: a pair costs O(9 S²).
    """

    def __init__(
        self, model: FaceModel, *, gaze: bool = True, extra_deltas: np.ndarray | None = None
    ) -> None:
        n_shapes, n_vertices = model.n_shapes, model.n_vertices
        extra = np.zeros((0, n_vertices, 3)) if extra_deltas is None else np.asarray(extra_deltas)
        if extra.ndim != 3 or extra.shape[1:] != (n_vertices, 3):
            raise ShapeError(
                f"extra_deltas must have shape (C, {n_vertices}, 3); got {extra.shape}"
            )
        self.n_vertices = n_vertices
        self.n_shapes = n_shapes
        self.n_weights = n_shapes + len(extra)
        self.gaze = model.rig.gaze if gaze else None
        pivots = model._eye_pivots if self.gaze is not None else []
        deltas = np.concatenate(
            [model.deltas.reshape(n_shapes, -1), extra.reshape(len(extra), 3 * n_vertices)]
        ).astype(np.float64)
        gram = deltas @ deltas.T
        # Per eyeball: T (3, 3, S+1, S+1), the second moments of X = [neutral − centre; deltas].
        moments = []
        for sl, centre in pivots:
            if len(extra) and np.any(extra[:, sl] != 0):
                raise ShapeError(
                    "extra deltas (correctives) that move the eyeballs are not supported: the "
                    "eyeballs rotate with the gaze"
                )
            d_eye = model.deltas[:, sl].astype(np.float64)  # (S, n_eye, 3)
            flat = d_eye.reshape(n_shapes, -1)
            gram[:n_shapes, :n_shapes] -= flat @ flat.T
            x = np.concatenate([(model.neutral[sl] - centre)[None].astype(np.float64), d_eye])
            moments.append(np.einsum("kvi,lvj->ijkl", x, x, optimize=True))
        self.gram = gram
        self._moments = moments

    def _rotations(self, w: np.ndarray) -> np.ndarray:
        from emogen.model.face import gaze_rotations

        if self.gaze is None:
            return np.broadcast_to(np.eye(3), (len(w), 3, 3))
        yaw, pitch = self.gaze.angles(w)
        return gaze_rotations(yaw, pitch)

    def squared_sum(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Σ_n ‖v₁,ₙ − v₂,ₙ‖² per face pair: a, b (n_faces, S) or (S,), broadcast."""
        a = np.asarray(a, dtype=np.float64)
        b = np.asarray(b, dtype=np.float64)
        if a.shape[-1] != self.n_weights or b.shape[-1] != self.n_weights:
            raise ShapeError(
                f"VertexRMS needs weights (n_faces, {self.n_weights}); got {a.shape} and {b.shape}"
            )
        a2, b2 = np.broadcast_arrays(np.atleast_2d(a), np.atleast_2d(b))
        dw = a2 - b2
        total = ((dw @ self.gram) * dw).sum(-1)
        if self._moments:
            a2, b2 = a2[:, : self.n_shapes], b2[:, : self.n_shapes]
            ha = np.concatenate([np.ones((len(a2), 1)), a2], axis=1)
            hb = np.concatenate([np.ones((len(b2), 1)), b2], axis=1)
            m = self._rotations(a2).transpose(0, 2, 1) @ self._rotations(b2)  # R₁ᵀ R₂
            for t in self._moments:
                diag = t[[0, 1, 2], [0, 1, 2]].sum(0)  # Σᵢ Tᵢᵢ: ‖x‖² = α̂ (Σᵢ Tᵢᵢ) α̂ᵀ
                qa = ((ha @ diag) * ha).sum(-1)
                qb = ((hb @ diag) * hb).sum(-1)
                z = np.einsum("bk,ijkl->bijl", ha, t, optimize=True)
                cross = np.einsum("bij,bijl,bl->b", m, z, hb, optimize=True)
                total += qa + qb - 2.0 * cross
        return np.maximum(total, 0.0)

    def __call__(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """vrtx_rms (eq. 13) per face pair: a, b (n_faces, S) or (S,) full weights → (n_faces,)."""
        d = np.sqrt(self.squared_sum(a, b) / self.n_vertices)
        return d[0] if np.ndim(a) == 1 and np.ndim(b) == 1 else d
