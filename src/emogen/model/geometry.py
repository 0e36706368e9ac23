"""Mesh geometry shared by every layer: vertex normals and the least-squares sphere."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from scipy import sparse

__all__ = ["sphere_fit", "triangle_incidence", "vertex_normals"]

# Normals shorter than this (a vertex on no triangle of non-zero area) come out as zero.
_TINY = 1e-20


def triangle_incidence(
    triangles: np.ndarray, n_vertices: int, dtype: type = np.float64
) -> sparse.csr_matrix:
    """(n_vertices, n_triangles) 0/1 matrix: row v marks the triangles that use vertex v."""
    from scipy import sparse  # here: importing this module (every study command) stays light

    tri = np.asarray(triangles, dtype=np.int64)
    rows = tri.reshape(-1)
    cols = np.repeat(np.arange(len(tri)), 3)
    return sparse.csr_matrix(
        (np.ones(len(rows), dtype=dtype), (rows, cols)), shape=(n_vertices, len(tri))
    )


def vertex_normals(
    vertices: np.ndarray,
    triangles: np.ndarray,
    *,
    dtype: type = np.float64,
    incidence: sparse.csr_matrix | None = None,
) -> np.ndarray:
    """Area-weighted unit vertex normals.

    vertices : (V, 3) or (B, V, 3); triangles : (T, 3) → normals of the same shape as
    ``vertices``, computed in ``dtype`` (zero for a vertex on no triangle of non-zero area).
    ``incidence``: :func:`triangle_incidence` of ``triangles`` (in ``dtype``), when the caller
    keeps it to compute normals of many batches.
    """
    v: np.ndarray = np.asarray(vertices, dtype=dtype)
    batch = v[None] if v.ndim == 2 else v
    n_v = batch.shape[1]
    tri = np.asarray(triangles, dtype=np.int64)
    a = batch[:, tri[:, 0]]
    face = np.cross(batch[:, tri[:, 1]] - a, batch[:, tri[:, 2]] - a)  # (B, T, 3), |·| = 2 area
    if incidence is None:
        incidence = triangle_incidence(tri, n_v, dtype)
    summed = incidence @ face.transpose(1, 0, 2).reshape(len(tri), -1)
    normals: np.ndarray = (
        np.asarray(summed, dtype=dtype).reshape(n_v, len(batch), 3).transpose(1, 0, 2)
    )
    length = np.linalg.norm(normals, axis=-1, keepdims=True)
    out: np.ndarray = np.zeros(normals.shape, dtype=dtype)
    np.divide(normals, length, out=out, where=length > _TINY)
    return out[0] if v.ndim == 2 else out


def sphere_fit(points: np.ndarray) -> tuple[np.ndarray, float]:
    """Least-squares sphere of points (n, 3): (centre (3,), radius), in float64.

    Solves 2 p·c + (r² − |c|²) = |p|² for c and r² − |c|².
    """
    p = np.asarray(points, dtype=np.float64)
    a = np.c_[2 * p, np.ones(len(p))]
    sol, *_ = np.linalg.lstsq(a, (p**2).sum(1), rcond=None)
    centre = sol[:3]
    return centre, float(np.sqrt(sol[3] + centre @ centre))
