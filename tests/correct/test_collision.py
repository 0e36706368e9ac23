"""Lip layout, collision corrective shapes, anchors, detection and depths (eqs. 2–4)."""

from __future__ import annotations

import numpy as np
import pytest

from emogen.correct import collision as col
from emogen.correct.lips import geodesic
from tests.correct.reference_detect import anchor_points, reference_detect


def local(model, layout, weights):  # type: ignore[no-untyped-def]
    w = np.atleast_2d(weights)
    return model.evaluate(w)[:, layout.vertices].astype(np.float64)


def test_mouth_line_and_sides(ict_model, mouth) -> None:
    n = ict_model.neutral
    assert n[mouth.upper, 1].mean() > n[mouth.lower, 1].mean()
    # both chains run corner to corner, sharing the corners
    assert {mouth.upper[0], mouth.upper[-1]} == {mouth.lower[0], mouth.lower[-1]}
    assert mouth.half_width == pytest.approx(2.3, abs=0.2)
    q = len(mouth.upper) // 4
    assert np.all(mouth.side[mouth.upper[q:-q]] == 1.0)
    q = len(mouth.lower) // 4
    assert np.all(mouth.side[mouth.lower[q:-q]] == -1.0)
    # the face's lowest lip vertex at the midline is on the lower lip, the nose on neither
    near = np.isfinite(mouth.d_upper)
    assert near.sum() > 5000


def test_geodesic_on_a_strip() -> None:
    # a 1 × 4 strip of unit squares: distance from the left edge is the x coordinate
    v = np.array([[x, y, 0.0] for x in range(5) for y in range(2)], dtype=float)
    tris = []
    for x in range(4):
        a, b, c, d = 2 * x, 2 * x + 1, 2 * x + 2, 2 * x + 3
        tris += [(a, c, d), (a, d, b)]
    d = geodesic(v, np.array(tris), np.array([0, 1]))
    np.testing.assert_allclose(d, v[:, 0])


def test_zones_overlap_and_sum_to_one() -> None:
    x = np.linspace(-4, 4, 801)
    z = col.zone_weights(x, 0.0, 2.0)
    np.testing.assert_allclose(z.sum(0), 1.0, atol=1e-12)
    assert np.all(z >= 0)
    # outer left is the subject's left (+x), and neighbours overlap
    assert z[0, -1] == 1.0 and z[3, 0] == 1.0
    assert ((z[0] > 0) & (z[1] > 0)).any() and ((z[1] > 0) & (z[2] > 0)).any()
    # symmetric: zone k at x is zone 3-k at -x
    np.testing.assert_allclose(z[:, ::-1], z[::-1], atol=1e-12)


def test_collision_shapes_move_only_the_lips_in_their_directions(
    ict_model, ict_correctives, mouth
) -> None:
    d = ict_correctives.collision_deltas
    assert d.shape == (8, ict_model.n_vertices, 3)
    lip, teeth = d[:4], d[4:]
    upper = mouth.side >= 1
    lower = mouth.side <= -1
    assert np.all(lip[..., 1][:, upper] >= 0) and np.all(lip[..., 1][:, lower] <= 0)
    assert np.all(lip[..., [0, 2]] == 0)
    assert np.all(teeth[..., [0, 1]] == 0) and np.all(teeth[..., 2] >= 0)
    assert np.all(teeth[..., 2][:, upper] == 0)
    moved = np.flatnonzero(np.abs(d).sum(axis=(0, 2)) > 0)
    face = ict_model.regions["face"]
    socket = ict_model.regions["mouth_socket"]
    inside = ((moved >= face.v_start) & (moved < face.v_stop)) | (
        (moved >= socket.v_start) & (moved < socket.v_stop)
    )
    assert inside.all()  # teeth, gums, eyes, head never move
    # four zones together lift/lower the lip middle by the full amplitude
    mid = mouth.upper[len(mouth.upper) // 2]
    assert lip[:, mid, 1].sum() == pytest.approx(col.LIP_AMPLITUDE, rel=1e-6)
    # mirror symmetry: zone k on the left is zone 3-k on the right
    x = ict_model.base_neutral[:, 0]
    left = np.flatnonzero((x > 0.5) & upper)[:50]
    twin = [
        int(
            np.argmin(
                np.linalg.norm(
                    ict_model.base_neutral - ict_model.base_neutral[i] * [-1, 1, 1], axis=1
                )
            )
        )
        for i in left
    ]
    np.testing.assert_allclose(lip[0, left], lip[3, twin], atol=1e-4)


def test_anchors_are_barycentric_points_on_their_regions(ict_model, ict_correctives) -> None:
    lay = ict_correctives.layout
    for kind, names in ((col.LIP, ("face", "mouth_socket")), (col.TEETH, None)):
        bary = lay.anchor_bary[kind]
        np.testing.assert_allclose(bary.sum(1), 1.0)
        assert np.all(bary >= 0)
        tri = ict_model.faces[lay.anchor_triangle[kind]]
        np.testing.assert_array_equal(lay.vertices[lay.anchors[kind]], tri)
        if names is None:  # upper incisors and canines only
            teeth = [
                r
                for n, r in ict_model.regions.items()
                if n.startswith("tooth_upper") and ("incisor" in n or "canine" in n)
            ]
            ok = np.zeros(len(tri), dtype=bool)
            for r in teeth:
                ok |= (tri.min(1) >= r.v_start) & (tri.max(1) < r.v_stop)
            assert ok.all() and len(tri) > 200
        else:
            assert len(tri) > 500


def test_neutral_has_no_collision(ict_model, ict_correctives) -> None:
    lay = ict_correctives.layout
    det = col.detect(local(ict_model, lay, np.zeros(ict_model.n_shapes)), lay)
    assert det.within.sum() == 0 and len(det.constraints.depth) == 0


@pytest.mark.parametrize(
    ("shape", "kind"),
    [("mouthShrugLower", col.LIP), ("mouthPress", col.LIP), ("mouthRollLower", col.TEETH)],
)
def test_single_shapes_that_collide_are_detected_with_positive_depths(
    ict_model, ict_correctives, shape, kind
) -> None:
    lay = ict_correctives.layout
    w = ict_model.rig.weights_from_names({shape: 1.0})
    det = col.detect(local(ict_model, lay, w), lay)
    assert det.within[0, kind] > 0
    c = det.constraints
    assert np.all(c.depth > 0) and np.any(c.kind == kind)
    a = col.depth_jacobian(
        c, lay, ict_correctives.collision_deltas[:, lay.vertices].astype(np.float64)
    )
    # every collision corrective only separates (δa ≥ 0), and each pair is served by its type
    assert np.all(a >= -1e-9)
    rows = c.kind == kind
    served = a[rows][:, :4] if kind == col.LIP else a[rows][:, 4:]
    assert np.all(served.sum(1) > 0)


def test_depth_is_the_distance_to_the_partner_along_the_axis(ict_model, ict_correctives) -> None:
    lay = ict_correctives.layout
    pts = local(ict_model, lay, ict_model.rig.weights_from_names({"mouthShrugLower": 1.0}))
    det = col.detect(pts, lay)
    c = det.constraints
    for kind in (col.LIP, col.TEETH):
        rows = np.flatnonzero(c.kind == kind)[:20]
        anchor = anchor_points(pts, lay, kind)[0, c.anchor[rows]]
        partner = np.einsum("mkd,mk->md", pts[0][lay.lower[c.partner[rows]]], c.partner_bary[rows])
        ax = col.AXIS[kind]
        np.testing.assert_allclose(
            c.depth[rows], col.NEGATIVE[kind] * (partner[:, ax] - anchor[:, ax]), atol=1e-9
        )
        others = [d for d in range(3) if d != ax]
        np.testing.assert_allclose(partner[:, others], anchor[:, others], atol=1e-9)


def _by_face(c):  # type: ignore[no-untyped-def]
    """The pairs in (face, kind, anchor) order, as one comparable array."""
    rows = np.lexsort((c.anchor, c.kind, c.face))
    ids = np.c_[c.face, c.kind, c.anchor, c.partner].astype(np.float64)
    return np.column_stack([ids, c.partner_bary, c.depth, c.within])[rows]


def test_compiled_detection_equals_the_array_reference_on_ga_faces(
    ict_model, ict_correctives, ga_weights
) -> None:
    """Within counts and every pair (partner, barycentric point, depth) agree with the same rules
    written as whole-array numpy over line_hits (tests/correct/reference_detect.py), on ≥ 500
    GA faces of which many collide, and on the faces as corrected part-way."""
    lay = ict_correctives.layout
    weights = ga_weights[0]
    pts = local(ict_model, lay, weights)
    deltas = ict_correctives.collision_deltas[:, lay.vertices].astype(np.float64)
    half = pts + (np.full((len(pts), 8), 0.3) @ deltas.reshape(8, -1)).reshape(pts.shape)
    for batch, least in ((pts, 100), (half, 10)):
        got, want = col.detect(batch, lay, margin=0.03), reference_detect(batch, lay, margin=0.03)
        np.testing.assert_array_equal(got.within, want.within)
        assert got.colliding.sum() >= least
        g, w = _by_face(got.constraints), _by_face(want.constraints)
        assert g.shape == w.shape and len(g) >= 10 * least
        np.testing.assert_array_equal(g[:, :4], w[:, :4])
        np.testing.assert_allclose(g[:, 4:], w[:, 4:], rtol=0, atol=1e-12)
