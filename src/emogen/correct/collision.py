"""Collision correctives (paper Section III-A, eqs. 2–4): shapes, anchors, detection, depths.

Two collision types, each corrected by four corrective shapes (zones outer left, inner left,
inner right, outer right):

* **lip** — the upper lip inside the lower lip; corrected by moving the lips apart vertically
  (upper lip up, lower lip down). Its constraints are vertical (model y).
* **teeth** — the upper front teeth inside the lower lip; corrected by moving the lower lip
  outward (model +z). Its constraints are outward.

Directions: the lower lip's corrective motion is *positive* (down for lip, outward for teeth),
so the *negative ray* from an anchor points up (lip) or inward (teeth).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from emogen.correct.lips import UPPER_FRONT_TEETH, MouthGeometry
from emogen.correct.raycast import LineHits, line_hits

LIP, TEETH = 0, 1
TYPES = ("lip", "teeth")
ZONES = ("outer_left", "inner_left", "inner_right", "outer_right")
Y, Z = 1, 2
# Per type: the constraint axis and the sign of the negative ray along it.
AXIS = {LIP: Y, TEETH: Z}
NEGATIVE = {LIP: +1.0, TEETH: -1.0}

LOWER_LIP_RADIUS = 1.8  # cm of geodesic distance from the lower chain: the lower lip surface
UPPER_ANCHOR_RADIUS = 1.5  # cm from the upper chain: upper lip anchors
CROWN_FRACTION = 0.45  # the lower part of each tooth's height that carries anchors (the crown)
CONTACT_TOLERANCE = 0.02  # cm: an anchor this close to the lip surface is touching, not inside
CELL_FACTOR = 1.0  # ray-casting bin size, in median lower-lip edge lengths
DETECT_CHUNK = 16  # faces per ray-casting batch (bounds the candidate arrays)

# The corrective shapes: amplitude (cm at weight 1) and geodesic falloff (full up to r_full,
# smoothstep to zero at r_zero) per moving part.
LIP_AMPLITUDE = 0.5  # each lip, so the lips part by twice this
TEETH_AMPLITUDE = 1.5  # the lower lip, outward
UPPER_FALLOFF = (0.6, 1.8)
LOWER_FALLOFF = (1.0, 2.4)


def corrective_names() -> tuple[str, ...]:
    """``collision_lip_outer_left`` … ``collision_teeth_outer_right`` (type-major order)."""
    return tuple(f"collision_{t}_{z}" for t in TYPES for z in ZONES)


def zone_weights(x: np.ndarray, centre: float, half_width: float) -> np.ndarray:
    """(4, n) overlapping zone weights over x: outer left, inner left, inner right, outer right.

    With u = (x − centre) / half_width (the corners at ±1; +x is the subject's left), zone k is a
    raised-cosine bump of half-width ½ centred at u = 0.75, 0.25, −0.25, −0.75; neighbours
    overlap by half and the four sum to one everywhere (the outer zones stay at one beyond
    their centres), so all four at weight w move the whole mouth by w.
    """
    u = (np.asarray(x, dtype=np.float64) - centre) / half_width
    centres = np.array([0.75, 0.25, -0.25, -0.75])
    dist = np.abs(u[None, :] - centres[:, None])
    w = np.where(dist < 0.5, np.cos(np.pi * dist) ** 2, 0.0)
    w[0, u >= 0.75] = 1.0
    w[3, u <= -0.75] = 1.0
    return w


def falloff(d: np.ndarray, r_full: float, r_zero: float) -> np.ndarray:
    """1 up to ``r_full``, smoothstep down to 0 at ``r_zero`` (0 for inf)."""
    t = np.clip((np.asarray(d, dtype=np.float64) - r_full) / (r_zero - r_full), 0.0, 1.0)
    return 1.0 - t * t * (3.0 - 2.0 * t)


def collision_deltas(neutral: np.ndarray, mouth: MouthGeometry) -> np.ndarray:
    """The eight collision corrective shapes, (8, V, 3) float32 offsets from the neutral.

    Lip type, zone k: upper lip up, lower lip down, ``LIP_AMPLITUDE`` × zone_k(x) × falloff
    (geodesic distance to the lip's chain) × side (+1 upper, −1 lower, 0 at the corners).
    Teeth type, zone k: the lower lip outward (+z), ``TEETH_AMPLITUDE`` × zone_k(x) × falloff ×
    max(0, −side). Nothing else moves.
    """
    zones = zone_weights(neutral[:, 0], mouth.centre_x, mouth.half_width)  # (4, V)
    side = mouth.side
    up = falloff(mouth.d_upper, *UPPER_FALLOFF) * np.clip(side, 0.0, 1.0)
    down = falloff(mouth.d_lower, *LOWER_FALLOFF) * np.clip(-side, 0.0, 1.0)
    out = np.zeros((8, len(neutral), 3), dtype=np.float32)
    out[:4, :, Y] = LIP_AMPLITUDE * zones * (up - down)
    out[4:, :, Z] = TEETH_AMPLITUDE * zones * down
    return out


@dataclass(frozen=True)
class CollisionLayout:
    """Anchors and the lower lip surface, in a compact local vertex numbering.

    vertices : (L,) int, the model vertices the detector reads (local index = position here)
    lower : (Tl, 3) int local, the lower lip triangles the rays are cast against
    lower_vertices : (Vl,) int local, their vertices
    anchors[type] : (Na, 3) int local, each anchor's triangle; anchor_bary[type] : (Na, 3)
    anchor_triangle[type] : (Na,) int, the anchor's triangle in ``model.faces`` (paper: t_i)
    cell : float, the ray-casting bin size (cm)
    """

    vertices: np.ndarray
    lower: np.ndarray
    lower_vertices: np.ndarray
    anchors: tuple[np.ndarray, np.ndarray]
    anchor_bary: tuple[np.ndarray, np.ndarray]
    anchor_triangle: tuple[np.ndarray, np.ndarray]
    cell: float


def _anchors(
    polygons: np.ndarray, chosen: np.ndarray, vertices: np.ndarray, faces: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Anchors (triangle index in ``faces``, barycentric (N, 3)) at the centre of each chosen
    polygon and at each of ``vertices``.

    A quad's centre is the midpoint of its a–c diagonal (shared by both of its triangles),
    barycentric (½, 0, ½) on its first triangle (a, b, c); a triangle's is its centroid. A vertex
    is a corner of the first triangle that uses it (barycentric 1 there, 0 elsewhere).
    """
    from emogen.model.io.obj import triangulate

    _, owner = triangulate(polygons)
    first = np.searchsorted(owner, chosen)
    quad = polygons[chosen, 3] >= 0
    bary = np.where(quad[:, None], [0.5, 0.0, 0.5], [1 / 3, 1 / 3, 1 / 3])
    # each vertex: the corner it is of the first triangle that uses it
    tri_idx, corner = [], []
    for c in range(3):
        hit = np.isin(faces[:, c], vertices)
        tri_idx.append(np.flatnonzero(hit))
        corner.append(np.full(int(hit.sum()), c))
    t = np.concatenate(tri_idx)
    at = np.concatenate(corner)
    _, pick = np.unique(faces[t, at], return_index=True)
    t, at = t[pick], at[pick]
    vbary = np.zeros((len(t), 3))
    vbary[np.arange(len(t)), at] = 1.0
    return np.r_[first, t], np.vstack([bary, vbary])


def collision_layout(
    neutral: np.ndarray,
    faces: np.ndarray,
    polygons: np.ndarray,
    regions: dict,
    mouth: MouthGeometry,
) -> CollisionLayout:
    """Choose the anchors and the lower lip surface (see docs/correctives.md).

    * lower lip: face and mouth-socket triangles on the lower side (mean side < 0) within
      ``LOWER_LIP_RADIUS`` of the lower chain;
    * upper lip anchors: the vertices of the face and mouth socket wholly on the upper lip
      (side 1: not in the corners, where the lips join) within ``UPPER_ANCHOR_RADIUS`` of the
      upper chain, and the centres of the polygons made of such vertices;
    * teeth anchors: the vertices of the upper incisors and canines in the lower
      ``CROWN_FRACTION`` of each tooth's height (ICT's teeth carry their roots in the gums),
      and the centres of the polygons made of such vertices.
    """
    lip_tris = mouth.lip_triangles
    lower = lip_tris[
        (mouth.side[lip_tris].mean(1) < 0) & (mouth.d_lower[lip_tris].max(1) <= LOWER_LIP_RADIUS)
    ]
    on_lip = np.zeros(len(neutral), dtype=bool)
    on_lip[np.unique(lip_tris)] = True
    upper_v = on_lip & (mouth.side >= 1.0) & (mouth.d_upper <= UPPER_ANCHOR_RADIUS)
    lip_polys = np.concatenate(
        [np.arange(regions[r].p_start, regions[r].p_stop) for r in ("face", "mouth_socket")]
    )
    crown_v = np.zeros(len(neutral), dtype=bool)
    teeth_polys = []
    for name in UPPER_FRONT_TEETH:
        r = regions[name]
        ys = neutral[r.vertices, 1]
        crown_v[
            r.v_start + np.flatnonzero(ys <= ys.min() + CROWN_FRACTION * (ys.max() - ys.min()))
        ] = True
        teeth_polys.append(np.arange(r.p_start, r.p_stop))

    def whole(polys: np.ndarray, mask: np.ndarray) -> np.ndarray:
        q = polygons[polys]
        return polys[np.where(q >= 0, mask[np.maximum(q, 0)], True).all(1)]

    up_idx, up_bary = _anchors(polygons, whole(lip_polys, upper_v), np.flatnonzero(upper_v), faces)
    th_idx, th_bary = _anchors(
        polygons, whole(np.concatenate(teeth_polys), crown_v), np.flatnonzero(crown_v), faces
    )

    used = np.unique(
        np.concatenate([lower.reshape(-1), faces[up_idx].reshape(-1), faces[th_idx].reshape(-1)])
    )
    local = np.full(len(neutral), -1, dtype=np.int64)
    local[used] = np.arange(len(used))
    edge = np.linalg.norm(neutral[lower[:, 1]] - neutral[lower[:, 0]], axis=1)
    return CollisionLayout(
        vertices=used,
        lower=local[lower],
        lower_vertices=np.unique(local[lower]),
        anchors=(local[faces[up_idx]], local[faces[th_idx]]),
        anchor_bary=(up_bary, th_bary),
        anchor_triangle=(up_idx, th_idx),
        cell=float(CELL_FACTOR * np.median(edge)),
    )


def anchor_points(local: np.ndarray, layout: CollisionLayout, kind: int) -> np.ndarray:
    """(B, Na, 3) anchor positions from local vertices (B, L, 3)."""
    tri = local[:, layout.anchors[kind]]  # (B, Na, 3, 3)
    return np.einsum("bnkd,nk->bnd", tri, layout.anchor_bary[kind])


@dataclass(frozen=True)
class Constraints:
    """Intersection pairs of a batch (one row per pair; eq. 3–4 inputs).

    face, kind, anchor : (M,) int — batch row, collision type (0 lip, 1 teeth), anchor index
    partner : (M,) int, lower lip triangle (local numbering of ``layout.lower``)
    partner_bary : (M, 3) float; depth : (M,) float, δb (cm, ≥ 0)
    within : (M,) bool, the anchor is within the lower lip (False: passed through)
    """

    face: np.ndarray
    kind: np.ndarray
    anchor: np.ndarray
    partner: np.ndarray
    partner_bary: np.ndarray
    depth: np.ndarray
    within: np.ndarray


@dataclass(frozen=True)
class Detection:
    """within : (B, 2) int, anchors within the lower lip per type; constraints: the pairs."""

    within: np.ndarray
    constraints: Constraints

    @property
    def colliding(self) -> np.ndarray:
        """(B,) bool: a collision is detected (some anchor within the lower lip)."""
        return self.within.sum(1) > 0


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


def _empty_constraints() -> Constraints:
    z = np.zeros(0, dtype=np.int64)
    return Constraints(z, z, z, z, np.zeros((0, 3)), np.zeros(0), np.zeros(0, dtype=bool))


def _concat(parts: list[Constraints], offsets: list[int]) -> Constraints:
    if not parts:
        return _empty_constraints()
    return Constraints(
        face=np.concatenate([c.face + o for c, o in zip(parts, offsets, strict=True)]),
        kind=np.concatenate([c.kind for c in parts]),
        anchor=np.concatenate([c.anchor for c in parts]),
        partner=np.concatenate([c.partner for c in parts]),
        partner_bary=np.concatenate([c.partner_bary for c in parts]),
        depth=np.concatenate([c.depth for c in parts]),
        within=np.concatenate([c.within for c in parts]),
    )


def detect(local: np.ndarray, layout: CollisionLayout, *, margin: float = 0.0) -> Detection:
    """Detect collisions and build the intersection pairs of a batch (in chunks of faces).

    local : (B, L, 3) float64 positions of ``layout.vertices``. See :func:`detect_chunk`.
    """
    parts = [
        detect_chunk(local[s : s + DETECT_CHUNK], layout, margin=margin)
        for s in range(0, len(local), DETECT_CHUNK)
    ]
    if len(parts) == 1:
        return parts[0]
    return Detection(
        within=np.concatenate([p.within for p in parts]).reshape(-1, 2),
        constraints=_concat(
            [p.constraints for p in parts], list(range(0, len(local), DETECT_CHUNK))
        ),
    )


def _subset(hits: LineHits, ids: np.ndarray) -> LineHits:
    """Hits of a subset query renumbered to the full query list (``ids``: subset → full)."""
    return LineHits(ids[hits.point], hits.triangle, hits.t, hits.facing, hits.bary)


def detect_chunk(local: np.ndarray, layout: CollisionLayout, *, margin: float = 0.0) -> Detection:
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
    tris = local[:, layout.lower]
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
    hy = line_hits(pts_q, face_q, tris, Y, layout.cell, 1)
    _, up = _nearest(hy, n, +1.0)
    candidate = up > 0
    if not candidate.any():
        return Detection(within=within, constraints=_empty_constraints())
    busy = np.zeros(b_n, dtype=bool)
    busy[face_q[candidate]] = True
    cast = np.flatnonzero(candidate | ((kind_q == TEETH) & busy[face_q]))
    need = np.where(kind_q[cast] == TEETH, -1, 2)
    hz = _subset(line_hits(pts_q[cast], face_q[cast], tris, Z, layout.cell, need), cast)
    inside_q = candidate & _within(hy, hz, n)
    np.add.at(within, (face_q, kind_q), inside_q)
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
    return Detection(within=within, constraints=_concat(parts, [0] * len(parts)))


def offsets_at(deltas_local: np.ndarray, triangles: np.ndarray, bary: np.ndarray) -> np.ndarray:
    """Corrective offsets at barycentric points (eq. 2): (C, L, 3) local deltas → (M, C, 3)."""
    corners = deltas_local[:, triangles]  # (C, M, 3, 3)
    return np.einsum("cmkd,mk->mcd", corners, bary)


def depth_jacobian(
    constraints: Constraints, layout: CollisionLayout, deltas_local: np.ndarray
) -> np.ndarray:
    """δa (eqs. 3–4): depth removed per unit weight of each corrective, (M, C).

    Lip pairs: (ΔB(p_upper) − ΔB(p_lower))_y; teeth pairs: (ΔB(p_lower) − ΔB(p_teeth))_z —
    i.e. the anchor's offset minus the partner's along the type's axis, signed so that
    separating them along the negative ray counts positive.
    """
    c = constraints
    out = np.zeros((len(c.depth), deltas_local.shape[0]))
    for kind in (LIP, TEETH):
        rows = np.flatnonzero(c.kind == kind)
        if len(rows) == 0:
            continue
        a = offsets_at(
            deltas_local,
            layout.anchors[kind][c.anchor[rows]],
            layout.anchor_bary[kind][c.anchor[rows]],
        )
        p = offsets_at(deltas_local, layout.lower[c.partner[rows]], c.partner_bary[rows])
        out[rows] = NEGATIVE[kind] * (a[..., AXIS[kind]] - p[..., AXIS[kind]])
    return out
