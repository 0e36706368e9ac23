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

from dataclasses import dataclass, field

import numpy as np
from numba import njit

from emogen.correct.lips import UPPER_FRONT_TEETH, MouthGeometry
from emogen.correct.raycast import (
    bin_triangles_in,
    cell_hits,
    cell_of,
    gather_triangles,
    grow,
    hit_buffers,
)

LIP, TEETH = 0, 1
TYPES = ("lip", "teeth")
ZONES = ("outer_left", "inner_left", "inner_right", "outer_right")
X, Y, Z = 0, 1, 2
# Per type: the constraint axis and the sign of the negative ray along it.
AXIS = {LIP: Y, TEETH: Z}
NEGATIVE = {LIP: +1.0, TEETH: -1.0}

LOWER_LIP_RADIUS = 1.8  # cm of geodesic distance from the lower chain: the lower lip surface
UPPER_ANCHOR_RADIUS = 1.5  # cm from the upper chain: upper lip anchors
CROWN_FRACTION = 0.45  # the lower part of each tooth's height that carries anchors (the crown)
CONTACT_TOLERANCE = 0.02  # cm: an anchor this close to the lip surface is touching, not inside
CELL_FACTOR = 1.0  # ray-casting bin size, in median lower-lip edge lengths

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
    #: both types' anchors together, as the compiled detector takes them (made once)
    anchor_table: tuple[np.ndarray, np.ndarray, np.ndarray] = field(
        init=False, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        object.__setattr__(self, "anchor_table", _anchor_table(self))


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


@njit(cache=True, nogil=True, inline="always")
def _summarise(
    n: int, hit_t: np.ndarray, hit_facing: np.ndarray, negative: float
) -> tuple[float, float, float, float, int, int]:  # pragma: no cover - compiled
    """One line's hits: the nearest on the + side (distance, facing) and on the − side (ties:
    the last such hit), and along the ``negative`` ray the first hit leaving the lower lip
    (buffer index or −1; ties: the first such hit) with its rank among the hits on that side
    (0: the first surface met, the point is within; 1: after entering once, passed through)."""
    d_plus, f_plus, d_minus, f_minus = np.inf, 0.0, np.inf, 0.0
    exit_h, exit_d = -1, np.inf
    for h in range(n):
        t = hit_t[h]
        if t > 0.0 and t <= d_plus:
            d_plus, f_plus = t, hit_facing[h]
        if -t > 0.0 and -t <= d_minus:
            d_minus, f_minus = -t, hit_facing[h]
        d = negative * t
        if d > 0.0 and negative * hit_facing[h] > 0.0 and d < exit_d:
            exit_h, exit_d = h, d
    rank = 0
    if exit_h >= 0:
        for h in range(n):
            d = negative * hit_t[h]
            if d > 0.0 and (d < exit_d or (d == exit_d and h < exit_h)):
                rank += 1
    return d_plus, f_plus, d_minus, f_minus, exit_h, rank


@njit(cache=True, nogil=True)
def detect_faces(
    local: np.ndarray,
    lower: np.ndarray,
    lower_vertices: np.ndarray,
    anchor_corners: np.ndarray,
    anchor_bary: np.ndarray,
    anchor_kind: np.ndarray,
    cell: float,
    tolerance: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover - compiled
    """Detection of a batch, face by face (see :func:`detect`); compiled.

    Anchors of both types are given together (``anchor_kind``: 0 lip, 1 teeth; lip first).
    Returns within (B, 2), and per pair (face, anchor (global), partner triangle, within flag)
    (M, 4) and (partner barycentric u, v (2nd, 3rd corner), distance along the negative ray)
    (M, 3).
    """
    n_faces, n_tris, n_anc = local.shape[0], lower.shape[0], anchor_corners.shape[0]
    within = np.zeros((n_faces, 2), dtype=np.int64)
    tri = np.empty((n_tris, 3, 3))
    b_tri, b_t, b_facing, b_u, b_v = hit_buffers(n_tris)
    q_anchor = np.empty(n_anc, dtype=np.int64)
    q_point = np.empty((n_anc, 3))
    q_near = np.empty((n_anc, 8))  # y: d+, f+, d−, f−; z: d+, f+, d−, f−
    q_candidate = np.zeros(n_anc, dtype=np.bool_)
    q_inside = np.zeros(n_anc, dtype=np.bool_)
    q_exit = np.empty((n_anc, 5))  # partner triangle, u, v, distance, rank (triangle −1: none)
    pair_ids = np.empty((1024, 4), dtype=np.int64)  # face, anchor, partner, within
    pair_values = np.empty((1024, 3))  # partner u, v, distance
    n_out = 0
    p = np.empty(3)
    for b in range(n_faces):
        verts = local[b]
        lo = np.full(3, np.inf)
        hi = np.full(3, -np.inf)
        finite = True
        for v in lower_vertices:  # the lower lip's triangles' corners, each once
            for d in range(3):
                lo[d] = min(lo[d], verts[v, d])
                hi[d] = max(hi[d], verts[v, d])
                finite = finite and np.isfinite(verts[v, d])
        gather_triangles(verts, lower, tri)
        grid_y = bin_triangles_in(tri, Y, cell, lo[Z], lo[X], hi[Z], hi[X], finite)
        n_q = 0
        busy = False
        for n in range(n_anc):
            kind = anchor_kind[n]
            for d in range(3):
                p[d] = (
                    anchor_bary[n, 0] * verts[anchor_corners[n, 0], d]
                    + anchor_bary[n, 1] * verts[anchor_corners[n, 1], d]
                    + anchor_bary[n, 2] * verts[anchor_corners[n, 2], d]
                )
            # the lower lip's bounding box, open on the negative ray's side (an anchor may have
            # passed through the lower lip)
            inside_box = True
            for d in range(3):
                if p[d] < lo[d] and not (kind == LIP and d == Y):
                    inside_box = False
                if p[d] > hi[d] and not (kind == TEETH and d == Z):
                    inside_box = False
            if not inside_box:
                continue
            q = n_q
            n_q += 1
            q_anchor[q] = n
            for d in range(3):
                q_point[q, d] = p[d]
            dp, fp, dm, fm, ex, rank = np.inf, 0.0, np.inf, 0.0, -1, 0  # no hit
            key = cell_of(grid_y, Y, p, 1)
            if key >= 0:
                h = cell_hits(tri, Y, grid_y, key, p, b_tri, b_t, b_facing, b_u, b_v)
                dp, fp, dm, fm, ex, rank = _summarise(h, b_t, b_facing, 1.0)
            q_near[q, 0], q_near[q, 1], q_near[q, 2], q_near[q, 3] = dp, fp, dm, fm
            q_near[q, 4], q_near[q, 5], q_near[q, 6], q_near[q, 7] = np.inf, 0.0, np.inf, 0.0
            q_exit[q, 0] = -1.0
            if kind == LIP and ex >= 0:
                q_exit[q, 0], q_exit[q, 1], q_exit[q, 2] = b_tri[ex], b_u[ex], b_v[ex]
                q_exit[q, 3], q_exit[q, 4] = b_t[ex], rank
            # a point inside the lower lip has the lip's top above it, seen from inside
            q_candidate[q] = fp > 0.0
            busy = busy or q_candidate[q]
        if not busy:
            continue
        grid_z = bin_triangles_in(tri, Z, cell, lo[X], lo[Y], hi[X], hi[Y], finite)
        count_lip, count_teeth = 0, 0
        for q in range(n_q):
            kind = anchor_kind[q_anchor[q]]
            if q_candidate[q] or kind == TEETH:
                need = -1 if kind == TEETH else 2
                for d in range(3):
                    p[d] = q_point[q, d]
                dp, fp, dm, fm, ex, rank = np.inf, 0.0, np.inf, 0.0, -1, 0  # no hit
                key = cell_of(grid_z, Z, p, need)
                if key >= 0:
                    h = cell_hits(tri, Z, grid_z, key, p, b_tri, b_t, b_facing, b_u, b_v)
                    dp, fp, dm, fm, ex, rank = _summarise(h, b_t, b_facing, -1.0)
                q_near[q, 4], q_near[q, 5], q_near[q, 6], q_near[q, 7] = dp, fp, dm, fm
                if kind == TEETH:
                    q_exit[q, 0] = -1.0
                    if ex >= 0:
                        q_exit[q, 0], q_exit[q, 1], q_exit[q, 2] = b_tri[ex], b_u[ex], b_v[ex]
                        q_exit[q, 3], q_exit[q, 4] = -b_t[ex], rank
            # within: along y or z the nearest surfaces on both sides are left (seen from
            # inside), or ≥ 2 rays meet the lower lip and all from inside; deeper than the
            # contact tolerance
            exits, entries, both, depth = 0, 0, False, np.inf
            for k in (0, 4):
                out_plus = q_near[q, k + 1] > 0.0
                out_minus = q_near[q, k + 3] < 0.0
                exits += out_plus + out_minus
                entries += (q_near[q, k + 1] < 0.0) + (q_near[q, k + 3] > 0.0)
                if out_plus:
                    depth = min(depth, q_near[q, k])
                if out_minus:
                    depth = min(depth, q_near[q, k + 2])
                both = both or (out_plus and out_minus)
            inside = q_candidate[q] and (both or (exits >= 2 and entries == 0))
            q_inside[q] = inside and depth > tolerance
            if q_inside[q]:
                if kind == LIP:
                    count_lip += 1
                else:
                    count_teeth += 1
        within[b, 0], within[b, 1] = count_lip, count_teeth
        if count_lip + count_teeth == 0:
            continue
        # the pairs: within anchors and anchors that passed through, with their first exit
        for q in range(n_q):
            if q_exit[q, 0] < 0 or not (q_inside[q] or q_exit[q, 4] == 1.0):
                continue
            if n_out == len(pair_ids):
                pair_ids = grow(pair_ids, 2 * n_out)
                pair_values = grow(pair_values, 2 * n_out)
            pair_ids[n_out, 0], pair_ids[n_out, 1] = b, q_anchor[q]
            pair_ids[n_out, 2], pair_ids[n_out, 3] = int(q_exit[q, 0]), q_inside[q]
            pair_values[n_out] = q_exit[q, 1:4]
            n_out += 1
    return within, pair_ids[:n_out], pair_values[:n_out]


def detect(local: np.ndarray, layout: CollisionLayout, *, margin: float = 0.0) -> Detection:
    """Detect collisions (paper: *within*) and build the intersection pairs (δb) of a batch.

    local : (B, L, 3) float64 positions of ``layout.vertices``.

    An anchor is *within* the lower lip when the lower lip's surface above it is seen from
    inside (its outward normal pointing away from the anchor), and along y or z the nearest
    surfaces on both sides are, or at least two of its four rays meet the lower lip and every one
    of them meets it from inside (the lower lip is an open sheet, cut where its region ends, so a
    ray can leave it before meeting its far side) — and it is deeper than
    ``CONTACT_TOLERANCE`` (no surface it is inside of closer along a ray): touching lips are not
    a collision. In a face with a collision, every within anchor, and every anchor that *passed
    through* the lower lip (along its negative ray: one surface entered, then one left), pairs
    with the first lower-lip surface left along its negative ray; δb is the distance to it
    (+ ``margin``).

    Cheap first: anchors outside the lower lip's bounding box (open on the negative ray's side)
    are skipped; the vertical rays come first, and only in a face where some anchor sees the
    lower lip above it from inside are the rays cast outward too (for those anchors, and for
    every teeth anchor, whose pairs are outward). Compiled (numba), face by face; the same
    rules as whole-array operations are kept in the tests as the reference.
    """
    local = np.ascontiguousarray(local, dtype=np.float64)
    if local.ndim != 3 or local.shape[1:] != (len(layout.vertices), 3):
        raise ValueError(
            f"local vertices must be (B, {len(layout.vertices)}, 3); got shape {local.shape}"
        )
    within, ids, values = detect_faces(
        local,
        layout.lower,
        layout.lower_vertices,
        *layout.anchor_table,
        layout.cell,
        CONTACT_TOLERANCE,
    )
    n_lip = len(layout.anchors[LIP])
    kind = (ids[:, 1] >= n_lip).astype(np.int64)
    u, v = values[:, 0], values[:, 1]
    return Detection(
        within=within,
        constraints=Constraints(
            face=ids[:, 0].copy(),
            kind=kind,
            anchor=ids[:, 1] - n_lip * kind,
            partner=ids[:, 2].copy(),
            partner_bary=np.stack([1.0 - u - v, u, v], axis=1),
            depth=values[:, 2] + margin,
            within=ids[:, 3].astype(bool),
        ),
    )


def _anchor_table(layout: CollisionLayout) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Both types' anchors together (lip first): corners (N, 3), barycentric (N, 3), kind (N,)."""
    corners = np.ascontiguousarray(np.concatenate(layout.anchors), dtype=np.int64)
    bary = np.ascontiguousarray(np.concatenate(layout.anchor_bary), dtype=np.float64)
    kind = np.repeat([LIP, TEETH], [len(layout.anchors[LIP]), len(layout.anchors[TEETH])])
    return corners, bary, kind.astype(np.int64)


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
