"""Wrinkles and folds from the geometry: the strain of the skin under a face's displacement.

Skin that a shape compresses folds: furrows run across the direction of compression (forehead
lines when the brows rise, glabellar furrows when they knit, crow's feet when the cheeks rise).
Nothing here is drawn by an artist: the strain comes from the model's own shape deltas, so an
imported model gets it too.

Per triangle of the textured skin, with rest positions ``p``, glTF UVs ``t`` and displacements
``d`` at its corners, the chart's Jacobians are ``F = [p1 − p0, p2 − p0] · A⁻¹`` and
``Fd = [d1 − d0, d2 − d0] · A⁻¹`` with ``A = [t1 − t0, t2 − t0]``; the **linear strain** in UV
axes is ``sym(Fᵀ Fd) / s²``, ``s²`` the chart's mean squared scale (cm² per UV unit²), so
``ε = (εuu, εvv, εuv)`` is dimensionless (−0.2: compressed by 20 % along that axis). Being
linear in ``d``, the strain of a face is the weighted sum of its shapes' strains — the browser
viewer blends per-target strains computed the same way (``web/viewer/strain.js``) with the
face's morph weights, the offscreen renderer takes the strain of the face's displacement
itself (correctives included); both are the same number. Vertices carry the area-weighted mean
of their triangles' strains; ``shade.glsl`` turns it into furrows (normal and a little cavity
colour) across the compressed directions.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import sparse

from emogen.model.face import FaceModel
from emogen.render.look import Look
from emogen.render.scene import FaceMesh

__all__ = [
    "StrainOperator",
    "principal_compression",
    "skin_strain_operator",
    "strain_operator",
    "wrinkle_amount",
]


@dataclass(frozen=True, eq=False)
class StrainOperator:
    """Linear strain of the drawn skin vertices of one mesh, as one sparse matrix.

    triangles : (T, 3) skin triangles in drawn-vertex numbering
    matrix : (3R, 3R) sparse: flattened displacements (R·3) → flattened vertex strains (R·3),
        the area-weighted mean of the per-triangle strains
    """

    triangles: np.ndarray
    matrix: sparse.csr_matrix

    def strain(self, displacement: np.ndarray) -> np.ndarray:
        """Drawn-vertex displacements (R, 3) cm → strain (R, 3) float32 (εuu, εvv, εuv)."""
        d = np.asarray(displacement, dtype=np.float32).reshape(-1)
        return np.asarray(self.matrix @ d, dtype=np.float32).reshape(-1, 3)


def _triangle_strains(
    jac: np.ndarray, inv: np.ndarray, tri: np.ndarray, n: int
) -> sparse.csr_matrix:
    """(3T, 3n) sparse: displacements → per-triangle (εuu, εvv, εuv). With edges d1 − d0 and
    d2 − d0, E[i, a] = Σ_j J[j, i] (A⁻¹[0, a] (d1 − d0)_j + A⁻¹[1, a] (d2 − d0)_j)."""
    n_tri = len(tri)
    # coefficient of corner k (1, 2) component j in E[i, a]: J[t, j, i] · A⁻¹[t, k − 1, a]
    e = np.einsum("tji,tka->tiakj", jac, inv)  # (T, 2, 2, 2 corners, 3)
    out = np.stack([e[:, 0, 0], e[:, 1, 1], 0.5 * (e[:, 0, 1] + e[:, 1, 0])], axis=1)
    coef = np.concatenate([-out.sum(axis=2, keepdims=True), out], axis=2)  # (T, 3, 3, 3)
    rows = 3 * np.arange(n_tri)[:, None, None, None] + np.arange(3)[None, :, None, None]
    cols = 3 * tri[:, None, :, None] + np.arange(3)[None, None, None, :]
    rows, cols = np.broadcast_arrays(rows, cols)
    return sparse.csr_matrix(
        (coef.reshape(-1), (rows.reshape(-1), cols.reshape(-1))), shape=(3 * n_tri, 3 * n)
    )


def strain_operator(
    rest: np.ndarray, uv: np.ndarray, triangles: np.ndarray, n_vertices: int
) -> StrainOperator:
    """The :class:`StrainOperator` of skin ``triangles (T, 3)`` over drawn vertices with rest
    positions ``rest (R, 3)`` cm and UVs ``uv (R, 2)``; degenerate UV triangles are skipped."""
    p = np.asarray(rest, dtype=np.float64)
    t = np.asarray(uv, dtype=np.float64)
    tri = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    a = np.stack([t[tri[:, 1]] - t[tri[:, 0]], t[tri[:, 2]] - t[tri[:, 0]]], axis=2)
    det = a[:, 0, 0] * a[:, 1, 1] - a[:, 0, 1] * a[:, 1, 0]
    ok = np.abs(det) > 1e-12
    tri, a, det = tri[ok], a[ok], det[ok]
    inv = (
        np.stack(
            [np.stack([a[:, 1, 1], -a[:, 0, 1]], 1), np.stack([-a[:, 1, 0], a[:, 0, 0]], 1)], 1
        )
        / det[:, None, None]
    )
    edges = np.stack([p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]]], axis=2)
    f = np.matmul(edges, inv)  # (T, 3, 2) cm per UV unit
    s2 = 0.5 * (f**2).sum(axis=(1, 2))
    area = 0.5 * np.linalg.norm(np.cross(edges[:, :, 0], edges[:, :, 1]), axis=1)
    rows = tri.reshape(-1)
    cols = np.repeat(np.arange(len(tri)), 3)
    m = sparse.csr_matrix((np.repeat(area, 3), (rows, cols)), shape=(n_vertices, len(tri)))
    total = np.asarray(m.sum(axis=1)).ravel()
    scale = np.divide(1.0, total, out=np.zeros_like(total), where=total > 0)
    average = sparse.kron(sparse.diags(scale) @ m, sparse.identity(3), format="csr")
    per_tri = _triangle_strains(f / s2[:, None, None], inv, tri, n_vertices)
    return StrainOperator(
        triangles=tri.astype(np.int32),
        matrix=sparse.csr_matrix(average @ per_tri, dtype=np.float32),
    )


def skin_strain_operator(model: FaceModel, mesh: FaceMesh, look: Look) -> StrainOperator:
    """The strain operator of the textured parts (skin and eye sockets) of ``mesh``: triangles
    keyed by their first corner's part, as the viewer's primitives are."""
    src = mesh.source
    part = mesh.part[src][mesh.drawn_triangles[:, 0]]
    skin = (part == look.shader["PART_SKIN"]) | (part == look.shader["PART_EYE_SOCKET"])
    return strain_operator(model.neutral[src], mesh.uv, mesh.drawn_triangles[skin], len(src))


def principal_compression(strain: np.ndarray) -> np.ndarray:
    """(n,) largest compression (−smallest eigenvalue, ≥ 0) of strains (n, 3)."""
    s = np.asarray(strain, dtype=np.float64)
    mean = 0.5 * (s[:, 0] + s[:, 1])
    radius = np.hypot(0.5 * (s[:, 0] - s[:, 1]), s[:, 2])
    return np.maximum(radius - mean, 0.0)


def wrinkle_amount(strain: np.ndarray, look: Look) -> np.ndarray:
    """(n,) in [0, 1]: how strongly ``shade.glsl`` furrows skin of strain (n, 3) — 0 below
    ``WRINKLE_START`` compression, 1 from ``WRINKLE_FULL`` (a smoothstep, as the shader)."""
    lo, hi = float(look.shader["WRINKLE_START"]), float(look.shader["WRINKLE_FULL"])
    x = np.clip((principal_compression(strain) - lo) / (hi - lo), 0.0, 1.0)
    return x * x * (3 - 2 * x)
