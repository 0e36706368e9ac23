"""Vertex normals and the sphere fit against plain references."""

from __future__ import annotations

import numpy as np

from emogen.model.geometry import sphere_fit, triangle_incidence, vertex_normals


def _loop_normals(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Reference: one triangle at a time, each adding its area-weighted normal to its corners."""
    acc = np.zeros((len(vertices), 3))
    for a, b, c in triangles:
        n = np.cross(vertices[b] - vertices[a], vertices[c] - vertices[a])
        for v in (a, b, c):
            acc[v] += n
    out = np.zeros_like(acc)
    for v in range(len(acc)):
        length = np.sqrt(acc[v] @ acc[v])
        if length > 0:
            out[v] = acc[v] / length
    return out


def _mesh(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    grid = np.stack(np.meshgrid(np.arange(6.0), np.arange(5.0)), -1).reshape(-1, 2)
    verts = np.c_[grid, rng.normal(0, 0.3, len(grid))]
    quads = [
        (r * 6 + c, r * 6 + c + 1, (r + 1) * 6 + c + 1, (r + 1) * 6 + c)
        for r in range(4)
        for c in range(5)
    ]
    tris = np.array([t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))])
    extra = np.r_[verts, [[9.0, 9.0, 9.0]]]  # a vertex on no triangle: normal zero
    return extra, tris


def test_vertex_normals_equal_a_per_triangle_loop() -> None:
    verts, tris = _mesh(np.random.default_rng(0))
    want = _loop_normals(verts, tris)
    np.testing.assert_allclose(vertex_normals(verts, tris), want, atol=1e-12)
    assert np.all(vertex_normals(verts, tris)[-1] == 0)
    batch = np.stack([verts, verts * 2 + 1])
    got = vertex_normals(batch, tris)
    np.testing.assert_allclose(got[1], want, atol=1e-12)


def test_float32_with_a_kept_incidence_matches_float64() -> None:
    verts, tris = _mesh(np.random.default_rng(1))
    inc = triangle_incidence(tris, len(verts), np.float32)
    got = vertex_normals(verts[None], tris, dtype=np.float32, incidence=inc)
    assert got.dtype == np.float32 and got.shape == (1, *verts.shape)
    np.testing.assert_allclose(got[0], _loop_normals(verts, tris), atol=1e-5)


def test_sphere_fit_recovers_a_sphere() -> None:
    rng = np.random.default_rng(2)
    d = rng.normal(size=(200, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    centre, radius = sphere_fit(np.array([1.5, -2.0, 3.0]) + 1.25 * d)
    np.testing.assert_allclose(centre, [1.5, -2.0, 3.0], atol=1e-9)
    assert abs(radius - 1.25) < 1e-9
