"""Axis-aligned ray casting against a plain per-pair reference."""

from __future__ import annotations

import numpy as np
import pytest

from emogen.correct.raycast import AxisBins


def reference_hits(points, point_face, triangles, axis):
    """Every (point, triangle, t) crossing, one pair at a time (float64, no binning)."""
    a, c = (axis + 1) % 3, (axis + 2) % 3
    out = set()
    for q, (p, f) in enumerate(zip(points, point_face, strict=True)):
        for t_i, tri in enumerate(triangles[f]):
            m = np.array(
                [
                    [tri[1, a] - tri[0, a], tri[2, a] - tri[0, a]],
                    [tri[1, c] - tri[0, c], tri[2, c] - tri[0, c]],
                ]
            )
            if abs(np.linalg.det(m)) < 1e-12:
                continue
            u, v = np.linalg.solve(m, [p[a] - tri[0, a], p[c] - tri[0, c]])
            if u >= 0 and v >= 0 and u + v <= 1:
                hit = (
                    tri[0, axis]
                    + u * (tri[1, axis] - tri[0, axis])
                    + v * (tri[2, axis] - tri[0, axis])
                )
                out.add((q, t_i, round(hit - p[axis], 9)))
    return out


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_hits_match_plain_reference(axis) -> None:
    rng = np.random.default_rng(axis)
    b, t, q = 3, 40, 120
    centres = rng.uniform(-1, 1, size=(b, t, 1, 3))
    triangles = centres + rng.normal(scale=0.15, size=(b, t, 3, 3))
    points = rng.uniform(-1.2, 1.2, size=(q, 3))
    point_face = rng.integers(0, b, size=q)
    hits = AxisBins(triangles, axis, cell=0.1).hits(points, point_face)
    got = {
        (int(p), int(tr), round(float(d), 9))
        for p, tr, d in zip(hits.point, hits.triangle, hits.t, strict=True)
    }
    want = reference_hits(points, point_face, triangles, axis)
    assert got == want
    assert len(want) > 5
    # facing is the triangle normal's component along the axis
    tri = triangles[point_face[hits.point], hits.triangle]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    np.testing.assert_allclose(hits.facing, normal[:, axis], rtol=1e-9, atol=1e-12)
    # the barycentric point lies on the line through the query point
    bary = hits.bary
    on_tri = (
        tri[:, 0] + bary[:, :1] * (tri[:, 1] - tri[:, 0]) + bary[:, 1:] * (tri[:, 2] - tri[:, 0])
    )
    others = [k for k in range(3) if k != axis]
    np.testing.assert_allclose(on_tri[:, others], points[hits.point][:, others], atol=1e-9)


def test_need_only_drops_points_that_cannot_get_what_they_need() -> None:
    rng = np.random.default_rng(9)
    triangles = rng.uniform(0, 1, size=(1, 80, 1, 3)) + rng.normal(scale=0.1, size=(1, 80, 3, 3))
    points = rng.uniform(-0.2, 1.2, size=(300, 3))
    face = np.zeros(300, dtype=np.int64)
    bins = AxisBins(triangles, 2, cell=0.08)
    full = bins.hits(points, face)
    for need in (-1, 0, 1):
        part = bins.hits(points, face, need)
        kept = set(part.point.tolist())
        for p in range(300):
            ts = full.t[full.point == p]
            ok = {1: (ts > 0).any(), -1: (ts < 0).any(), 0: (ts > 0).any() and (ts < 0).any()}[need]
            if ok:  # a point that can have what it needs keeps all its hits
                assert p in kept
                assert sorted(part.t[part.point == p]) == sorted(ts)
