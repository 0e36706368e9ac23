"""The compiled ray casting (binning and probes, through the batch caster of the reference
detector) against a plain per-pair loop."""

from __future__ import annotations

import numpy as np
import pytest

from tests.correct.reference_detect import line_hits


def as_mesh(triangles):
    """(B, T, 3, 3) corners → vertices (B, 3T, 3) and triangles (T, 3) (no shared corners)."""
    b, t = triangles.shape[:2]
    return triangles.reshape(b, 3 * t, 3), np.arange(3 * t).reshape(t, 3)


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
    hits = line_hits(points, point_face, *as_mesh(triangles), axis, cell=0.1)
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
    full = line_hits(points, face, *as_mesh(triangles), 2, cell=0.08)
    for need in (-1, 0, 1):
        part = line_hits(points, face, *as_mesh(triangles), 2, cell=0.08, need=need)
        kept = set(part.point.tolist())
        for p in range(300):
            ts = full.t[full.point == p]
            ok = {1: (ts > 0).any(), -1: (ts < 0).any(), 0: (ts > 0).any() and (ts < 0).any()}[need]
            if ok:  # a point that can have what it needs keeps all its hits
                assert p in kept
                assert sorted(part.t[part.point == p]) == sorted(ts)


def test_a_face_with_non_finite_corners_has_no_hits_and_the_others_are_unaffected() -> None:
    rng = np.random.default_rng(3)
    triangles = rng.uniform(0, 1, size=(2, 30, 1, 3)) + rng.normal(scale=0.2, size=(2, 30, 3, 3))
    points = rng.uniform(0, 1, size=(200, 3))
    face = np.repeat([0, 1], 100)
    clean = line_hits(points, face, *as_mesh(triangles), 1, cell=0.1)
    bad = triangles.copy()
    bad[0, 4, 1, 2] = np.nan
    hits = line_hits(points, face, *as_mesh(bad), 1, cell=0.1)
    assert not np.any(hits.point < 100)
    keep = clean.point >= 100
    np.testing.assert_array_equal(hits.point, clean.point[keep])
    np.testing.assert_array_equal(hits.t, clean.t[keep])


def test_a_grid_too_fine_for_the_face_gets_coarser_cells_and_the_same_hits() -> None:
    """Cells of 1e-6 over a unit face would be 10¹² cells: the grid coarsens, hits stay exact."""
    rng = np.random.default_rng(4)
    triangles = rng.uniform(0, 1, size=(1, 25, 1, 3)) + rng.normal(scale=0.2, size=(1, 25, 3, 3))
    points = rng.uniform(0, 1, size=(150, 3))
    face = np.zeros(150, dtype=np.int64)
    hits = line_hits(points, face, *as_mesh(triangles), 0, cell=1e-6)
    got = {
        (int(p), int(t), round(float(d), 9))
        for p, t, d in zip(hits.point, hits.triangle, hits.t, strict=True)
    }
    assert got == reference_hits(points, face, triangles, 0) and len(got) > 5


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"axis": 3}, "axis must be 0, 1 or 2; got 3"),
        ({"cell": 0.0}, "cell must be positive; got 0.0"),
        ({"point_face": np.array([0, 2])}, r"point faces must lie in \[0, 1\); got 0…2"),
        ({"point_face": np.array([0])}, "2 points but 1 point faces"),
        ({"corners": np.array([[0, 1, 7]])}, r"triangle corners must lie in \[0, 3\)"),
    ],
)
def test_bad_arguments_are_named(kwargs, message) -> None:
    args = {
        "points": np.zeros((2, 3)),
        "point_face": np.array([0, 0]),
        "vertices": np.eye(3)[None],
        "corners": np.array([[0, 1, 2]]),
        "axis": 2,
        "cell": 0.1,
    }
    with pytest.raises(ValueError, match=message):
        line_hits(**(args | kwargs))
