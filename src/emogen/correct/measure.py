"""Measures of implausible geometry, independent of the correctives' own detector.

* :class:`Interpenetration` — upper front teeth and upper lip *vertices* inside a *closed*
  lower-lip volume, by generalised winding number (solid angles, Van Oosterom & Strackee 1983),
  deeper than a contact tolerance (Euclidean distance to the lower lip surface). The collision
  detector instead casts axis-aligned rays from anchor points (polygon centres) against the
  open lower-lip sheet; the two share only the notion of which skin is the lower lip.
* :class:`Plausibility` — the combinational correctives' measure: eyelid crossing (upper lid
  margin below the lower one), lip overlap (the upper inner lip line below the lower one) and
  extreme stretch: a face-skin edge stretched or compressed beyond the artist's envelope — more
  than ``ENVELOPE_FACTOR`` × the most any single shape at full weight stretches it (or less
  than the least it is compressed, divided by that factor). The single shapes are sculpted to
  be plausible; what a combination adds beyond them is the double counting that the
  combinational correctives remove.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from emogen.correct.lips import UPPER_FRONT_TEETH, MouthGeometry, boundary_loops, polygon_edges

VOLUME_RADIUS = 1.6  # cm from the lower chain: the lower lip tissue closed for the winding test
VOLUME_WIDTH = 0.85  # of the mouth's half width: the volume stops short of the corners
CONTACT = 0.02  # cm: a vertex inside the lower lip by less than this is touching it
CROSSING = 0.02  # cm: margins crossing by less than this are touching
ENVELOPE_FACTOR = 1.25  # beyond the single shapes' strain envelope by this factor: extreme


def _solid_angles(points: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Σ over triangles of the signed solid angle at each point / 4π: (P, 3), (T, 3, 3) → (P,).

    Van Oosterom & Strackee: tan(Ω/2) = a·(b×c) / (|a||b||c| + (a·b)|c| + (b·c)|a| + (c·a)|b|)
    with a, b, c the corners relative to the point; written per coordinate (P, T) arrays.
    """
    p = points.T[:, :, None]  # (3, P, 1)
    a = tri[:, 0].T[:, None, :] - p  # (3, P, T)
    b = tri[:, 1].T[:, None, :] - p
    c = tri[:, 2].T[:, None, :] - p
    la = np.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])
    lb = np.sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2])
    lc = np.sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2])
    det = (
        a[0] * (b[1] * c[2] - b[2] * c[1])
        + a[1] * (b[2] * c[0] - b[0] * c[2])
        + a[2] * (b[0] * c[1] - b[1] * c[0])
    )
    den = (
        la * lb * lc
        + (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) * lc
        + (b[0] * c[0] + b[1] * c[1] + b[2] * c[2]) * la
        + (c[0] * a[0] + c[1] * a[1] + c[2] * a[2]) * lb
    )
    return np.arctan2(det, den).sum(1) / (2.0 * np.pi)


def _point_triangle_distance(points: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Smallest Euclidean distance from each point (P, 3) to the triangles (T, 3, 3): (P,)."""
    best = np.full(len(points), np.inf)
    for k in range(0, len(points), 64):
        p = points[k : k + 64, None, :]
        a, b, c = tri[None, :, 0], tri[None, :, 1], tri[None, :, 2]
        ab, ac, ap = b - a, c - a, p - a
        n = np.cross(ab, ac)
        nn = np.maximum(np.einsum("ptd,ptd->pt", n, n), 1e-30)
        # projection onto the plane, barycentric coordinates of the foot
        t = np.einsum("ptd,ptd->pt", ap, n) / nn
        foot = p - t[..., None] * n
        d2 = np.einsum("ptd,ptd->pt", np.cross(b - foot, c - foot), n) / nn
        d3 = np.einsum("ptd,ptd->pt", np.cross(c - foot, a - foot), n) / nn
        inside = (d2 >= 0) & (d3 >= 0) & (d2 + d3 <= 1)
        dist = np.where(inside, np.abs(t) * np.sqrt(nn), np.inf)
        for e0, e1 in ((a, b), (b, c), (c, a)):  # otherwise the nearest edge point
            e = e1 - e0
            s = np.clip(
                np.einsum("ptd,ptd->pt", p - e0, e)
                / np.maximum(np.einsum("ptd,ptd->pt", e, e), 1e-30),
                0.0,
                1.0,
            )
            q = e0 + s[..., None] * e
            dist = np.minimum(dist, np.sqrt(np.einsum("ptd,ptd->pt", p - q, p - q)))
        best[k : k + 64] = dist.min(1)
    return best


def _zipper(a: np.ndarray, b: np.ndarray, ta: np.ndarray, tb: np.ndarray) -> np.ndarray:
    """Triangles (K, 3) joining chain ``a`` to chain ``b`` (both running the same way, by the
    parameters ``ta``, ``tb`` in [0, 1]); oriented so that a boundary loop made of ``a``
    followed by ``b`` reversed is closed consistently."""
    i = j = 0
    out = []
    while i < len(a) - 1 or j < len(b) - 1:
        step_a = j == len(b) - 1 or (i < len(a) - 1 and ta[i + 1] <= tb[j + 1])
        if step_a:
            out.append((a[i + 1], a[i], b[j]))
            i += 1
        else:
            out.append((a[i], b[j], b[j + 1]))
            j += 1
    return np.array(out, dtype=np.int64)


def _arc_param(points: np.ndarray) -> np.ndarray:
    seg = np.linalg.norm(np.diff(points, axis=0), axis=1)
    t = np.r_[0.0, np.cumsum(seg)]
    return t / t[-1] if t[-1] > 0 else t


def close_lower_lip(neutral: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Triangles closing the lower lip sheet (one boundary loop) into a volume.

    The loop runs round the sheet's cut edges: over the lip at each side cut, and along the
    skin and the lining at the bottom. Split at the two side cuts' highest points, it gives a
    skin chain and a lining chain; a zipper between them (by arc length) caps the lip's root
    and both side cross-sections.
    """
    loops = boundary_loops(np.c_[triangles, np.full(len(triangles), -1)])
    if len(loops) != 1:
        raise ValueError(f"the lower lip sheet must have one boundary loop; got {len(loops)}")
    loop = loops[0]
    x, y = neutral[loop, 0], neutral[loop, 1]
    left = np.flatnonzero(x < np.median(x))
    right = np.flatnonzero(x >= np.median(x))
    i0, i1 = left[np.argmax(y[left])], right[np.argmax(y[right])]
    i0, i1 = min(i0, i1), max(i0, i1)
    a = loop[i0 : i1 + 1]
    b = np.r_[loop[i1:], loop[: i0 + 1]][::-1]
    return _zipper(a, b, _arc_param(neutral[a]), _arc_param(neutral[b]))


@dataclass(frozen=True)
class Interpenetration:
    """The independent interpenetration test (module docstring).

    lower : (T, 3) int, the lower-lip sheet; cap : (K, 3) int, the triangles closing it
    points : (P,) int, the tested vertices (upper front teeth crowns and the upper lip)
    """

    lower: np.ndarray
    cap: np.ndarray
    points: np.ndarray
    n_teeth_points: int

    @classmethod
    def build(cls, neutral: np.ndarray, regions: dict, mouth: MouthGeometry) -> Interpenetration:
        tris = mouth.lip_triangles
        u = np.abs(neutral[:, 0] - mouth.centre_x) / mouth.half_width
        keep = (mouth.side < 0) & (mouth.d_lower <= VOLUME_RADIUS) & (u <= VOLUME_WIDTH)
        lower = tris[keep[tris].all(1)]
        cap = close_lower_lip(neutral, lower)
        teeth = []
        for name in UPPER_FRONT_TEETH:
            r = regions[name]
            ys = neutral[r.vertices, 1]
            v = np.arange(r.v_start, r.v_stop)
            teeth.append(v[ys <= ys.min() + 0.5 * (ys.max() - ys.min())])
        lip_v = np.unique(tris)
        lip_v = lip_v[(mouth.side[lip_v] >= 1.0) & (mouth.d_upper[lip_v] <= 1.5)]
        teeth_v = np.concatenate(teeth)
        return cls(lower, cap, np.r_[teeth_v, lip_v], len(teeth_v))

    def closed_surface(self, verts: np.ndarray) -> np.ndarray:
        """(T', 3, 3) the lower lip triangles of one face plus the fans closing its loops."""
        return np.concatenate([verts[self.lower], verts[self.cap]])

    def depths(self, verts: np.ndarray) -> np.ndarray:
        """(P,) depth of each tested vertex inside the lower lip (0 outside), for one face."""
        surf = self.closed_surface(verts).astype(np.float32)
        pts = verts[self.points].astype(np.float32)
        lo, hi = surf.reshape(-1, 3).min(0), surf.reshape(-1, 3).max(0)
        cand = np.flatnonzero(np.all((pts > lo) & (pts < hi), axis=1))
        out = np.zeros(len(pts))
        if len(cand) == 0:
            return out
        wind = np.concatenate(
            [_solid_angles(pts[cand[k : k + 64]], surf) for k in range(0, len(cand), 64)]
        )
        inside = cand[np.abs(wind) > 0.5]
        if len(inside):
            out[inside] = _point_triangle_distance(
                pts[inside], verts[self.lower].astype(np.float64)
            )
        return out

    def penetrating(self, verts: np.ndarray) -> np.ndarray:
        """(B,) bool over faces (B, V, 3): some tested vertex is inside deeper than ``CONTACT``."""
        return np.array([bool((self.depths(v) > CONTACT).any()) for v in verts])


def _chains(neutral: np.ndarray, loop: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Split a closed loop at its points of extreme x: (upper chain, lower chain)."""
    x = neutral[loop, 0]
    i0, i1 = sorted((int(np.argmin(x)), int(np.argmax(x))))
    a, b = loop[i0 : i1 + 1], np.r_[loop[i1:], loop[: i0 + 1]]
    return (a, b) if neutral[a, 1].mean() > neutral[b, 1].mean() else (b, a)


def crossing_depth(verts: np.ndarray, upper: np.ndarray, lower: np.ndarray) -> np.ndarray:
    """(B,) how far the upper chain dips below the lower chain at the same x (0 if it doesn't)."""
    out = np.zeros(len(verts))
    for i, v in enumerate(verts):
        lx, ly = v[lower, 0], v[lower, 1]
        order = np.argsort(lx)
        ux, uy = v[upper, 0], v[upper, 1]
        ok = (ux > lx.min()) & (ux < lx.max())
        if ok.any():
            out[i] = max(0.0, float((np.interp(ux[ok], lx[order], ly[order]) - uy[ok]).max()))
    return out


@dataclass(frozen=True)
class Plausibility:
    """The combinational correctives' plausibility measure (module docstring)."""

    lids: tuple[tuple[np.ndarray, np.ndarray], ...]
    lips: tuple[np.ndarray, np.ndarray]
    edges: np.ndarray  # (E, 2) face-skin edges
    rest: np.ndarray  # (E,) their rest lengths
    longest: np.ndarray  # (E,) the largest length ratio a single shape at full weight gives
    shortest: np.ndarray  # (E,) the smallest

    @classmethod
    def build(
        cls,
        neutral: np.ndarray,
        polygons: np.ndarray,
        regions: dict,
        mouth: MouthGeometry,
        deltas: np.ndarray,
    ) -> Plausibility:
        """From the neutral, topology, regions and the shapes that define the envelope
        (deltas (S, V, 3): the shapes a face can activate)."""
        face = regions["face"]
        loops = boundary_loops(polygons[face.polygons])
        lids = []
        for eye in ("eyeball_left", "eyeball_right"):
            centre = neutral[regions[eye].vertices].mean(0)
            loop = min(loops, key=lambda lp: float(np.linalg.norm(neutral[lp].mean(0) - centre)))
            lids.append(_chains(neutral, loop))
        e = np.unique(np.sort(polygon_edges(polygons[face.polygons]), axis=1), axis=0)
        rest = np.linalg.norm(neutral[e[:, 0]] - neutral[e[:, 1]], axis=1)
        shaped = (
            neutral[None, e[:, 0]]
            + deltas[:, e[:, 0]]
            - neutral[None, e[:, 1]]
            - deltas[:, e[:, 1]]
        )
        ratio = np.linalg.norm(shaped, axis=2) / rest
        longest = np.maximum(ratio.max(0), 1.0)
        shortest = np.minimum(ratio.min(0), 1.0)
        return cls(tuple(lids), (mouth.upper, mouth.lower), e, rest, longest, shortest)

    def measure(self, verts: np.ndarray) -> dict[str, np.ndarray]:
        """Per face (B, V, 3): lid crossing and lip overlap depths (cm); ``excess``, the largest
        strain beyond the envelope (1 = at its edge); ``stretched_edges``, the edges beyond it by
        more than ``ENVELOPE_FACTOR``."""
        lid = np.maximum(*(crossing_depth(verts, u, lo) for u, lo in self.lids))
        lip = crossing_depth(verts, *self.lips)
        length = np.linalg.norm(verts[:, self.edges[:, 0]] - verts[:, self.edges[:, 1]], axis=2)
        ratio = length / self.rest
        excess = np.maximum(ratio / self.longest, self.shortest / np.maximum(ratio, 1e-9))
        return {
            "lid_crossing": lid,
            "lip_overlap": lip,
            "excess": excess.max(1),
            "stretched_edges": (excess > ENVELOPE_FACTOR).sum(1),
        }

    @staticmethod
    def implausible(m: dict[str, np.ndarray]) -> np.ndarray:
        """(B,) bool: lids or lips crossing beyond ``CROSSING``, or an extreme stretch."""
        return (
            (m["lid_crossing"] > CROSSING)
            | (m["lip_overlap"] > CROSSING)
            | (m["stretched_edges"] > 0)
        )
