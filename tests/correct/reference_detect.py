"""References for the compiled collision detector (:func:`emogen.correct.collision.detect`).

* :func:`line_hits` — every crossing of many axis-parallel lines with a batch of faces, through
  the compiled :func:`~emogen.correct.raycast.probe` (itself checked against a plain per-pair
  loop in test_raycast.py);
* :func:`reference_detect` — the detection rules as whole-array numpy over those hits (sorting,
  ``np.*.at``): the formulation the compiled detector replaced, where it walks each anchor's
  hits in a loop;
* :func:`anchor_points` — anchor positions by einsum.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from emogen.correct.collision import (
    AXIS,
    CONTACT_TOLERANCE,
    LIP,
    NEGATIVE,
    TEETH,
    CollisionLayout,
    Constraints,
    Detection,
    Y,
    Z,
)
from emogen.correct.raycast import (
    NO_FILTER,
    bin_triangles,
    gather_triangles,
    grow,
    hit_buffers,
    probe,
)


def anchor_points(local: np.ndarray, layout: CollisionLayout, kind: int) -> np.ndarray:
    """(B, Na, 3) anchor positions from local vertices (B, L, 3)."""
    tri = local[:, layout.anchors[kind]]  # (B, Na, 3, 3)
    return np.einsum("bnkd,nk->bnd", tri, layout.anchor_bary[kind])


@dataclass(frozen=True)
class LineHits:
    """Every crossing of the axis-parallel line through a query point with a triangle.

    point, triangle : (H,) int — query point and triangle (index within its face) of each hit
    t : (H,) float, hit coordinate minus point coordinate along the axis (signed distance)
    facing : (H,) float, the triangle normal's component along the axis (× twice its area);
      its sign says whether a ray going +axis enters (< 0) or leaves (> 0) the surface's inside
    bary : (H, 2) float, barycentric weights of the triangle's 2nd and 3rd corners at the hit

    Hits come grouped by face (in batch order), then by query point (in query order within the
    face), each point's in increasing triangle order.
    """

    point: np.ndarray
    triangle: np.ndarray
    t: np.ndarray
    facing: np.ndarray
    bary: np.ndarray

    def __len__(self) -> int:
        return len(self.t)


@njit(cache=True, nogil=True)
def _cast(  # pragma: no cover - compiled
    points: np.ndarray,
    order: np.ndarray,
    face_bounds: np.ndarray,
    vertices: np.ndarray,
    corners: np.ndarray,
    axis: int,
    cell: float,
    need: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """The hits of every query point (see :func:`line_hits`); compiled.

    order : the query indices grouped by face; face_bounds (B + 1,): face b's queries are
    ``order[face_bounds[b]:face_bounds[b + 1]]``. vertices (B, V, 3), corners (T, 3): the
    triangles of face b are ``vertices[b, corners]``. need (Q,) int8: 0, 1, −1, 2 or
    NO_FILTER. Returns the hits' (point, triangle) (H, 2) and (t, facing, u, v) (H, 4).
    """
    n_faces, n_tris = vertices.shape[0], corners.shape[0]
    tri = np.empty((n_tris, 3, 3))
    cap = max(64, 8 * len(points))
    ids = np.empty((cap, 2), dtype=np.int64)  # point, triangle
    values = np.empty((cap, 4))  # t, facing, u, v
    b_tri, b_t, b_facing, b_u, b_v = hit_buffers(n_tris)
    n_out = 0
    for b in range(n_faces):
        q0, q1 = face_bounds[b], face_bounds[b + 1]
        if q0 == q1 or n_tris == 0:
            continue
        gather_triangles(vertices[b], corners, tri)
        grid = bin_triangles(tri, axis, cell)
        for k in range(q0, q1):
            q = order[k]
            n = probe(tri, axis, grid, points[q], need[q], b_tri, b_t, b_facing, b_u, b_v)
            if n_out + n > len(ids):
                ids = grow(ids, 2 * (n_out + n))
                values = grow(values, 2 * (n_out + n))
            for h in range(n):
                ids[n_out, 0], ids[n_out, 1] = q, b_tri[h]
                values[n_out, 0], values[n_out, 1] = b_t[h], b_facing[h]
                values[n_out, 2], values[n_out, 3] = b_u[h], b_v[h]
                n_out += 1
    return ids[:n_out], values[:n_out]


def line_hits(
    points: np.ndarray,
    point_face: np.ndarray,
    vertices: np.ndarray,
    corners: np.ndarray,
    axis: int,
    cell: float,
    need: np.ndarray | int | None = None,
) -> LineHits:
    """Crossings of the lines along ``axis`` through ``points`` (Q, 3) of batch rows
    ``point_face`` (Q,) with the triangles ``corners`` (T, 3) of ``vertices`` (B, V, 3).

    cell : the bin size in the plane of the two other axes (about the triangles' size; only
    speed depends on it). need : None (every hit), or (Q,) / scalar int — which hits the caller
    needs: 0, surfaces on both sides of the point; +1, some on its + side; −1, some on its −
    side; 2, some on either side. A point whose cell's span along the axis cannot give that is
    skipped (no hits returned for it); a point that is kept gets every hit of its line.
    """
    if axis not in (0, 1, 2):
        raise ValueError(f"axis must be 0, 1 or 2; got {axis!r}")
    if not cell > 0:
        raise ValueError(f"cell must be positive; got {cell!r}")
    pts = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
    verts = np.ascontiguousarray(vertices, dtype=np.float64)
    tri_idx = np.ascontiguousarray(corners, dtype=np.int64).reshape(-1, 3)
    if verts.ndim != 3 or verts.shape[2] != 3:
        raise ValueError(f"vertices must be (B, V, 3); got shape {verts.shape}")
    if len(tri_idx) and (tri_idx.min() < 0 or tri_idx.max() >= verts.shape[1]):
        raise ValueError(f"triangle corners must lie in [0, {verts.shape[1]})")
    face = np.asarray(point_face, dtype=np.int64).reshape(-1)
    if len(face) != len(pts):
        raise ValueError(f"{len(pts)} points but {len(face)} point faces")
    if len(face) and (face.min() < 0 or face.max() >= len(verts)):
        raise ValueError(
            f"point faces must lie in [0, {len(verts)}); got {face.min()}…{face.max()}"
        )
    code = np.full(len(pts), NO_FILTER, dtype=np.int8)
    if need is not None:
        code[:] = np.broadcast_to(np.asarray(need, dtype=np.int8), code.shape)
    order = np.argsort(face, kind="stable")
    bounds = np.searchsorted(face[order], np.arange(len(verts) + 1)).astype(np.int64)
    ids, values = _cast(pts, order, bounds, verts, tri_idx, int(axis), float(cell), code)
    return LineHits(
        point=ids[:, 0], triangle=ids[:, 1], t=values[:, 0], facing=values[:, 1], bary=values[:, 2:]
    )


def _nearest(hits: LineHits, n: int, sign: float) -> tuple[np.ndarray, np.ndarray]:
    """Per query point: distance and facing of the nearest hit on the ``sign`` side."""
    side = sign * hits.t > 0
    dist = np.where(side, sign * hits.t, np.inf)
    best = np.full(n, np.inf)
    np.minimum.at(best, hits.point, dist)
    is_best = side & (dist == best[hits.point])
    facing = np.zeros(n)
    facing[hits.point[is_best]] = hits.facing[is_best]
    return best, facing


def _within(hy: LineHits, hz: LineHits, n: int) -> np.ndarray:
    """(Q,) bool: the query point is within the lower lip.

    The paper's test — on y or on z, lower-lip surfaces on both sides — with the surfaces'
    orientation: each nearest hit must be seen from inside (its outward normal pointing away
    from the point). The lower lip is an open sheet, cut where its region ends, so a ray can
    leave it before meeting its far side; a point is also within when at least two of its four
    rays meet the lower lip and every one of them meets it from inside. Either way the point
    must be deeper than ``CONTACT_TOLERANCE`` (no surface it is inside of closer along a ray):
    touching lips are not a collision. (:func:`reference_detect` further requires the surface
    above to be seen from inside: over 10,000 GA faces, no within anchor lacked it.)
    """
    exits = np.zeros(n, dtype=np.int64)
    entries = np.zeros(n, dtype=np.int64)
    depth = np.full(n, np.inf)
    both = np.zeros(n, dtype=bool)
    for hits in (hy, hz):
        leaving = []
        for sign in (+1.0, -1.0):
            dist, facing = _nearest(hits, n, sign)
            out = sign * facing > 0
            leaving.append(out)
            exits += out
            entries += sign * facing < 0
            depth = np.minimum(depth, np.where(out, dist, np.inf))
        both |= leaving[0] & leaving[1]
    inside = both | ((exits >= 2) & (entries == 0))
    return inside & (depth > CONTACT_TOLERANCE)


def _starts(k: np.ndarray) -> np.ndarray:
    """Boolean mask of the first element of each run of equal values in ``k``."""
    out = np.empty(len(k), dtype=bool)
    if len(k):
        out[0] = True
        np.not_equal(k[1:], k[:-1], out=out[1:])
    return out


def _first_exit(hits: LineHits, n: int, negative: float) -> tuple[np.ndarray, np.ndarray]:
    """Along each query's negative ray: the first hit leaving the lower lip, and its rank.

    Returns (hit index, or -1 when none; rank of that hit along the ray: 0 when it is the
    first surface met (the query is within), 1 after entering once (passed through)).
    """
    dist = negative * hits.t
    order = np.flatnonzero(dist > 0)
    order = order[np.lexsort((dist[order], hits.point[order]))]
    k = hits.point[order]
    exit_idx = np.full(n, -1, dtype=np.int64)
    exit_rank = np.full(n, -1, dtype=np.int64)
    if len(k) == 0:
        return exit_idx, exit_rank
    new = _starts(k)
    starts = np.flatnonzero(new)
    rank = np.arange(len(k)) - np.repeat(starts, np.diff(np.append(starts, len(k))))
    ex = np.flatnonzero(negative * hits.facing[order] > 0)
    kk = k[ex]
    first = ex[_starts(kk)] if len(ex) else ex
    exit_idx[k[first]] = order[first]
    exit_rank[k[first]] = rank[first]
    return exit_idx, exit_rank


def _subset(hits: LineHits, ids: np.ndarray) -> LineHits:
    """Hits of a subset query renumbered to the full query list (``ids``: subset → full)."""
    return LineHits(ids[hits.point], hits.triangle, hits.t, hits.facing, hits.bary)


def reference_detect(
    local: np.ndarray, layout: CollisionLayout, *, margin: float = 0.0
) -> Detection:
    """Detect collisions (paper: *within*) and build the intersection pairs (δb) of a batch.

    An anchor is *within* the lower lip (:func:`_within`) when the lower lip's surface above it
    is seen from inside, and along y or z both sides are, or every ray that meets the lower lip
    meets it from inside — deeper than ``CONTACT_TOLERANCE``. In a face with a collision, every
    within anchor, and every anchor that *passed through* the lower lip (along its negative ray:
    one surface entered, then one left), pairs with the first lower-lip surface left along its
    negative ray; δb is the distance to it (+ ``margin``).

    Cheap first: anchors outside the lower lip's bounding box (open on the negative ray's side)
    are skipped; the vertical rays come first, and only the anchors that see the lower lip
    above them from inside — few or none in a face without collision — are cast outward too (plus,
    in a face with a collision, the teeth anchors, for their pairs).
    """
    b_n = len(local)
    lv = local[:, layout.lower_vertices]
    lo, hi = lv.min(1), lv.max(1)
    q_pts, q_face, q_kind, q_anchor = [], [], [], []
    for kind in (LIP, TEETH):
        pts = anchor_points(local, layout, kind)
        ge, le = pts >= lo[:, None], pts <= hi[:, None]
        # open on the negative ray's side: an anchor may have passed through the lower lip
        (ge if NEGATIVE[kind] > 0 else le)[..., AXIS[kind]] = True
        face, anchor = np.nonzero(np.all(ge & le, axis=2))
        q_pts.append(pts[face, anchor])
        q_face.append(face)
        q_kind.append(np.full(len(face), kind))
        q_anchor.append(anchor)
    pts_q = np.concatenate(q_pts)
    face_q = np.concatenate(q_face)
    kind_q = np.concatenate(q_kind)
    anchor_q = np.concatenate(q_anchor)
    n = len(pts_q)
    within = np.zeros((b_n, 2), dtype=np.int64)
    # A point inside the lower lip has the lip's top above it, seen from inside.
    hy = line_hits(pts_q, face_q, local, layout.lower, Y, layout.cell, 1)
    _, up = _nearest(hy, n, +1.0)
    candidate = up > 0
    if not candidate.any():
        return Detection(within=within, constraints=_empty())
    busy = np.zeros(b_n, dtype=bool)
    busy[face_q[candidate]] = True
    cast = np.flatnonzero(candidate | ((kind_q == TEETH) & busy[face_q]))
    need = np.where(kind_q[cast] == TEETH, -1, 2)
    hz = line_hits(pts_q[cast], face_q[cast], local, layout.lower, Z, layout.cell, need)
    hz = _subset(hz, cast)
    inside_q = candidate & _within(hy, hz, n)
    within += np.bincount(2 * face_q[inside_q] + kind_q[inside_q], minlength=2 * b_n).reshape(
        b_n, 2
    )
    colliding = within.sum(1) > 0
    parts = []
    for kind in (LIP, TEETH):
        if not np.any((kind_q == kind) & colliding[face_q]):
            continue
        hits = hy if kind == LIP else hz
        exit_idx, exit_rank = _first_exit(hits, n, NEGATIVE[kind])
        q = np.flatnonzero(
            (kind_q == kind) & colliding[face_q] & (exit_idx >= 0) & (inside_q | (exit_rank == 1))
        )
        h = exit_idx[q]
        bary = hits.bary[h]
        parts.append(
            Constraints(
                face=face_q[q],
                kind=kind_q[q],
                anchor=anchor_q[q],
                partner=hits.triangle[h],
                partner_bary=np.concatenate([1.0 - bary.sum(1, keepdims=True), bary], axis=1),
                depth=NEGATIVE[kind] * hits.t[h] + margin,
                within=inside_q[q],
            )
        )
    return Detection(within=within, constraints=_concat(parts))


def _empty() -> Constraints:
    z = np.zeros(0, dtype=np.int64)
    return Constraints(z, z, z, z, np.zeros((0, 3)), np.zeros(0), np.zeros(0, dtype=bool))


def _concat(parts: list[Constraints]) -> Constraints:
    if not parts:
        return _empty()
    return Constraints(
        *(np.concatenate([getattr(c, f) for c in parts]) for f in Constraints.__dataclass_fields__)
    )
