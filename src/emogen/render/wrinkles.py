"""Wrinkles and folds from the geometry: the stretch of the skin under each shape.

Skin that a shape compresses folds: furrows run across the direction of compression (forehead
lines when the brows rise, glabellar furrows when they knit, crow's feet when the cheeks rise).
Nothing here is drawn by an artist: the stretch comes from the model's own shape deltas, so an
imported model gets it too.

**Rotation-free (co-rotational) strain.** Skin that only turns or moves — the chin and lips
carried round by ``jawOpen``, the cheeks lifted by ``mouthSmile`` — must not furrow; a linear
strain reads a turn by θ as a compression of 1 − cos θ and drew hatching there. Per triangle of
the textured skin, with rest positions ``p``, glTF UVs ``t`` and displaced positions ``p + d``,
the chart's Jacobians ``F₀ = [p1 − p0, p2 − p0] · A⁻¹`` and ``F₁`` (the same of ``p + d``), with
``A = [t1 − t0, t2 − t0]``, map UV to 3-D. ``F₀ = Q L`` (QR: ``Q`` an orthonormal frame of the
rest triangle whose first axis follows u, ``L`` upper triangular) gives the deformation gradient
``F = F₁ L⁻¹`` from the rest tangent plane; its polar decomposition ``F = R U`` splits off the
rotation ``R``, and the **Biot strain** ``U − I`` (``U = √(Fᵀ F)``, in closed form for 2 × 2)
is the strain, ``ε = (εuu, εvv, εuv)`` in the frame of the u and v axes, dimensionless (−0.2:
compressed by 20 % along that axis). It is exactly zero for any rigid motion of a triangle.

**One data path for both renderers.** A face's strain is the weighted sum of its morph
targets' strains (each target's at full weight): ``ε = Σₖ wₖ εₖ``, shapes then correctives in
the order of the viewer's GLB. The browser viewer blends the same per-target strains with the
face's morph weights (``web/viewer/strain.js``); the offscreen renderer with its shape and
corrective weights (:class:`TargetStrains`). A shape that only turns a patch of skin adds
nothing at any weight. Vertices carry the area-weighted mean of their triangles' strains, then
once more the mean over their triangles of those (two rings: one distorted triangle does not
stripe); ``shade.glsl`` turns it into furrows (normal and a little cavity colour) across the
compressed directions.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy import sparse

from emogen.model.face import FaceModel
from emogen.render.look import Look
from emogen.render.scene import FaceMesh

__all__ = [
    "StrainOperator",
    "TargetStrains",
    "biot_strain",
    "principal_compression",
    "skin_strain_operator",
    "strain_operator",
    "wrinkle_amount",
]


def biot_strain(c: np.ndarray) -> np.ndarray:
    """(T, 3) ``U − I`` as (uu, vv, uv) of right Cauchy–Green tensors ``c (T, 2, 2)``, ``U = √C``
    in closed form: ``√C = (C + √det C · I) / √(tr C + 2 √det C)``; 0 for a collapsed triangle."""
    det = np.maximum(c[:, 0, 0] * c[:, 1, 1] - c[:, 0, 1] * c[:, 1, 0], 0.0)
    s = np.sqrt(det)
    t = np.sqrt(np.maximum(c[:, 0, 0] + c[:, 1, 1] + 2.0 * s, 0.0))
    inv = np.divide(1.0, t, out=np.zeros_like(t), where=t > 1e-12)
    return np.stack(
        [(c[:, 0, 0] + s) * inv - 1.0, (c[:, 1, 1] + s) * inv - 1.0, c[:, 0, 1] * inv], axis=1
    )


def _edges(p: np.ndarray, tri: np.ndarray) -> np.ndarray:
    return np.stack([p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]]], axis=2)


@dataclass(frozen=True, eq=False)
class StrainOperator:
    """Rotation-free strain of the drawn skin vertices of one mesh.

    triangles : (T, 3) skin triangles in drawn-vertex numbering
    uv_inverse : (T, 2, 2) ``A⁻¹``; rest_jacobian : (T, 3, 2) ``F₀`` (cm per UV unit)
    frame_inverse : (T, 2, 2) ``L⁻¹`` (``F₀ = Q L``)
    average : (R, T) sparse: per-triangle values → the two-ring vertex means
    """

    triangles: np.ndarray
    uv_inverse: np.ndarray
    rest_jacobian: np.ndarray
    frame_inverse: np.ndarray
    average: sparse.csr_matrix

    def triangle_strain(self, displacement: np.ndarray) -> np.ndarray:
        """Drawn-vertex displacements (R, 3) cm → per-triangle Biot strain (T, 3)."""
        d = np.asarray(displacement, dtype=np.float64)
        f1 = self.rest_jacobian + _edges(d, self.triangles) @ self.uv_inverse
        g = f1 @ self.frame_inverse  # F = F₁ L⁻¹ (T, 3, 2)
        return biot_strain(np.matmul(np.transpose(g, (0, 2, 1)), g))

    def strain(self, displacement: np.ndarray) -> np.ndarray:
        """Drawn-vertex displacements (R, 3) cm → vertex strain (R, 3) float32 (εuu, εvv, εuv)."""
        return np.asarray(self.average @ self.triangle_strain(displacement), dtype=np.float32)


def _vertex_average(tri: np.ndarray, area: np.ndarray, n: int) -> sparse.csr_matrix:
    """(n, T): the area-weighted mean over a vertex's triangles of the triangles' mean over
    their corners of that (two rings)."""
    rows = tri.reshape(-1)
    cols = np.repeat(np.arange(len(tri)), 3)
    m = sparse.csr_matrix((np.repeat(area, 3), (rows, cols)), shape=(n, len(tri)))
    total = np.asarray(m.sum(axis=1)).ravel()
    scale = np.divide(1.0, total, out=np.zeros_like(total), where=total > 0)
    to_vertex = sparse.diags(scale) @ m
    to_triangle = sparse.csr_matrix(
        (np.full(len(rows), 1.0 / 3.0), (cols, rows)), shape=(len(tri), n)
    )
    return sparse.csr_matrix(to_vertex @ to_triangle @ to_vertex)


def strain_operator(
    rest: np.ndarray, uv: np.ndarray, triangles: np.ndarray, n_vertices: int
) -> StrainOperator:
    """The :class:`StrainOperator` of skin ``triangles (T, 3)`` over drawn vertices with rest
    positions ``rest (R, 3)`` cm and UVs ``uv (R, 2)``; degenerate triangles are skipped."""
    p = np.asarray(rest, dtype=np.float64)
    tri = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    a = _edges(np.asarray(uv, dtype=np.float64), tri)
    det = a[:, 0, 0] * a[:, 1, 1] - a[:, 0, 1] * a[:, 1, 0]
    safe = np.where(np.abs(det) > 1e-12, det, 1.0)
    inv = np.stack(
        [np.stack([a[:, 1, 1], -a[:, 0, 1]], 1), np.stack([-a[:, 1, 0], a[:, 0, 0]], 1)], 1
    )
    inv = inv / safe[:, None, None]
    f0 = _edges(p, tri) @ inv
    l11 = np.linalg.norm(f0[:, :, 0], axis=1)
    q1 = f0[:, :, 0] / np.where(l11 > 0, l11, 1.0)[:, None]
    l12 = (q1 * f0[:, :, 1]).sum(axis=1)
    l22 = np.linalg.norm(f0[:, :, 1] - l12[:, None] * q1, axis=1)
    ok = (np.abs(det) > 1e-12) & (l11 > 1e-9) & (l22 > 1e-9 * np.maximum(l11, 1.0))
    tri, inv, f0, l11, l12, l22 = tri[ok], inv[ok], f0[ok], l11[ok], l12[ok], l22[ok]
    zero = np.zeros_like(l11)
    frame_inv = np.stack(
        [np.stack([1.0 / l11, -l12 / (l11 * l22)], 1), np.stack([zero, 1.0 / l22], 1)], 1
    )
    area = 0.5 * np.linalg.norm(np.cross(*np.moveaxis(_edges(p, tri), 2, 0)), axis=1)
    return StrainOperator(
        triangles=tri.astype(np.int32),
        uv_inverse=inv,
        rest_jacobian=f0,
        frame_inverse=frame_inv,
        average=_vertex_average(tri, area, n_vertices),
    )


def skin_strain_operator(model: FaceModel, mesh: FaceMesh, look: Look) -> StrainOperator:
    """The strain operator of the textured parts (skin and eye sockets) of ``mesh``: triangles
    keyed by their first corner's part, as the viewer's primitives are."""
    src = mesh.source
    part = mesh.part[src][mesh.drawn_triangles[:, 0]]
    skin = (part == look.shader["PART_SKIN"]) | (part == look.shader["PART_EYE_SOCKET"])
    return strain_operator(model.neutral[src], mesh.uv, mesh.drawn_triangles[skin], len(src))


class TargetStrains:
    """The strains of a mesh's morph targets at full weight, each computed the first time a face
    uses it (as the viewer's ``StrainField.ensure``); a face's strain is their weighted sum.

    operator : the mesh's :class:`StrainOperator`; delta : target index → its drawn-vertex
    displacement (R, 3) cm (shapes first, then correctives, in the GLB's order)
    """

    def __init__(
        self, operator: StrainOperator, n_vertices: int, delta: Callable[[int], np.ndarray]
    ) -> None:
        self.operator = operator
        self.n_vertices = n_vertices
        self._delta = delta
        self._done: dict[int, np.ndarray] = {}

    def target(self, k: int) -> np.ndarray:
        """(R, 3) float32: target ``k``'s strain at full weight."""
        if k not in self._done:
            self._done[k] = self.operator.strain(self._delta(k))
        return self._done[k]

    def face(self, weights: np.ndarray) -> np.ndarray:
        """(R, 3) float32: ``Σₖ wₖ εₖ`` over the targets of nonzero weight ``weights (K,)``."""
        out = np.zeros((self.n_vertices, 3), dtype=np.float32)
        w = np.asarray(weights, dtype=np.float32)
        for k in np.flatnonzero(w):
            out += w[k] * self.target(int(k))
        return out


def principal_compression(strain: np.ndarray) -> np.ndarray:
    """(n,) largest compression (−smallest eigenvalue, ≥ 0) of strains (n, 3)."""
    s = np.asarray(strain, dtype=np.float64)
    mean = 0.5 * (s[:, 0] + s[:, 1])
    radius = np.hypot(0.5 * (s[:, 0] - s[:, 1]), s[:, 2])
    return np.maximum(radius - mean, 0.0)


def wrinkle_amount(strain: np.ndarray, look: Look) -> np.ndarray:
    """(n,) in [0, 1]: how strongly ``shade.glsl`` furrows skin of strain (n, 3) across its most
    compressed direction — 0 below ``WRINKLE_START`` compression, 1 from ``WRINKLE_FULL`` (a
    smoothstep, as the shader), times the slack across it (1 up to ``TAUT_START`` stretch, 0
    from ``TAUT_FULL``: taut skin stays smooth)."""
    sh = look.shader
    s = np.asarray(strain, dtype=np.float64)
    across = 0.5 * (s[:, 0] + s[:, 1]) + np.hypot(0.5 * (s[:, 0] - s[:, 1]), s[:, 2])

    def step(lo: str, hi: str, x: np.ndarray) -> np.ndarray:
        t = np.clip((x - float(sh[lo])) / (float(sh[hi]) - float(sh[lo])), 0.0, 1.0)
        return np.asarray(t * t * (3 - 2 * t))

    compressed = step("WRINKLE_START", "WRINKLE_FULL", principal_compression(s))
    return compressed * (1.0 - step("TAUT_START", "TAUT_FULL", across))
