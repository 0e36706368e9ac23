"""The collision detection as array logic over :func:`line_hits` — the formulation the
compiled detector (:func:`emogen.correct.collision.detect`) replaced, kept as its reference.

It casts every candidate ray of a batch through :func:`~emogen.correct.raycast.line_hits` and
decides *within*, exits and pairs with whole-array numpy operations (sorting, ``np.*.at``),
where the compiled detector walks each anchor's hits in a loop.
"""

from __future__ import annotations

import numpy as np

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
    anchor_points,
)
from emogen.correct.raycast import LineHits, line_hits, nearest


def _within(hy: LineHits, hz: LineHits, n: int) -> np.ndarray:
    """(Q,) bool: the query point is within the lower lip.

    The paper's test — on y or on z, lower-lip surfaces on both sides — with the surfaces'
    orientation: each nearest hit must be seen from inside (its outward normal pointing away
    from the point). The lower lip is an open sheet, cut where its region ends, so a ray can
    leave it before meeting its far side; a point is also within when at least two of its four
    rays meet the lower lip and every one of them meets it from inside. Either way the point
    must be deeper than ``CONTACT_TOLERANCE`` (no surface it is inside of closer along a ray):
    touching lips are not a collision. (:func:`detect_chunk` further requires the surface
    above to be seen from inside: over 10,000 GA faces, no within anchor lacked it.)
    """
    exits = np.zeros(n, dtype=np.int64)
    entries = np.zeros(n, dtype=np.int64)
    depth = np.full(n, np.inf)
    both = np.zeros(n, dtype=bool)
    for hits in (hy, hz):
        leaving = []
        for sign in (+1.0, -1.0):
            dist, facing = nearest(hits, n, sign)
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
    _, up = nearest(hy, n, +1.0)
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
