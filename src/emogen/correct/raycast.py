"""Axis-aligned ray casting against triangle sets, batched over faces, with planar binning.

The collision rays are axis-aligned (vertical and outward), so the line along axis k through a
point is a point in the plane of the two other axes. :class:`AxisBins` bins the triangles'
bounding boxes in that plane on a uniform grid (one grid per face, keys offset by the face
index, so a whole batch is one sort) and keeps, per cell, the span of the triangles along the
axis. A query point looks up its cell, is skipped when the span cannot give the hits it needs,
and is tested exactly (2-D barycentric coordinates, float64) against the few triangles there.
Every crossing of the whole line through the point is returned, on both sides.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class LineHits:
    """Every crossing of the axis-parallel line through a query point with a triangle.

    point, triangle : (H,) int — query point and triangle (index within its face) of each hit
    t : (H,) float, hit coordinate minus point coordinate along the axis (signed distance)
    facing : (H,) float, the triangle normal's component along the axis (× twice its area);
      its sign says whether a ray going +axis enters (< 0) or leaves (> 0) the surface's inside
    bary : (H, 2) float, barycentric weights of the triangle's 2nd and 3rd corners at the hit
    """

    point: np.ndarray
    triangle: np.ndarray
    t: np.ndarray
    facing: np.ndarray
    bary: np.ndarray

    def __len__(self) -> int:
        return len(self.t)


def _ranges(starts: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Concatenated aranges: [starts[0], …, starts[0]+counts[0]-1, starts[1], …]."""
    total = int(counts.sum())
    if total == 0:
        return np.zeros(0, dtype=np.int64)
    ends = np.cumsum(counts)
    offsets = np.repeat(ends - counts, counts)
    return np.repeat(starts, counts) + (np.arange(total) - offsets)


def _argsort_keys(keys: np.ndarray, n_keys: int) -> np.ndarray:
    """Argsort of bin keys: a radix sort (uint16, stable) when they fit, else a quicksort."""
    if n_keys <= 1 << 16:
        return np.argsort(keys.astype(np.uint16), kind="stable")
    return np.argsort(keys)


_DA = np.array([0, 0, 0, 1, 1, 1, 2, 2, 2])  # cell offsets of a box up to 3 × 3 cells
_DC = np.array([0, 1, 2, 0, 1, 2, 0, 1, 2])


def _min3(x: np.ndarray) -> np.ndarray:
    return np.minimum(np.minimum(x[0], x[1]), x[2])


def _max3(x: np.ndarray) -> np.ndarray:
    return np.maximum(np.maximum(x[0], x[1]), x[2])


class _Frame:
    """A batch's triangles seen along ``axis``: corners and edges per coordinate (contiguous
    rows, (3, B·T): numpy is slow on short strided axes), and the 2-D determinant (= the
    normal's component along the axis, × twice the area)."""

    def __init__(self, triangles: np.ndarray, axis: int) -> None:
        b_n, t_n = triangles.shape[:2]
        self.axis, self.t_n = axis, t_n
        self.a, self.c = a, c = (axis + 1) % 3, (axis + 2) % 3  # (a, c, axis) right-handed
        self.tri = tri = np.ascontiguousarray(triangles.reshape(b_n * t_n, 9).T).reshape(
            3, 3, b_n * t_n
        )
        self.corner = tri[0]
        self.ea = tri[1] - tri[0]
        self.eb = tri[2] - tri[0]
        self.det = self.ea[a] * self.eb[c] - self.ea[c] * self.eb[a]
        with np.errstate(divide="ignore"):
            self.inv_det = 1.0 / self.det

    def exact(self, points: np.ndarray, cp: np.ndarray, ct: np.ndarray) -> LineHits:
        """Test candidate pairs (point ``cp``, flat triangle ``ct``) exactly; keep the hits."""
        a, c, axis = self.a, self.c, self.axis
        corner, ea, eb = self.corner, self.ea, self.eb
        dpa = points[cp, a] - corner[a, ct]
        dpc = points[cp, c] - corner[c, ct]
        with np.errstate(invalid="ignore"):  # degenerate (edge-on) triangles give NaN: no hit
            u = (dpa * eb[c, ct] - dpc * eb[a, ct]) * self.inv_det[ct]
            v = (ea[a, ct] * dpc - ea[c, ct] * dpa) * self.inv_det[ct]
            hit = np.flatnonzero((u >= 0) & (v >= 0) & (u + v <= 1))
        ct, cp, u, v = ct[hit], cp[hit], u[hit], v[hit]
        coord = corner[axis, ct] + u * ea[axis, ct] + v * eb[axis, ct]
        return LineHits(
            point=cp,
            triangle=ct % self.t_n,
            t=coord - points[cp, axis],
            facing=self.det[ct],
            bary=np.stack([u, v], axis=1),
        )


def brute_hits(
    points: np.ndarray, point_face: np.ndarray, triangles: np.ndarray, axis: int
) -> LineHits:
    """Like :meth:`AxisBins.hits` (every hit) by testing each point against every triangle of
    its face: cheaper than binning for a handful of points."""
    t_n = triangles.shape[1]
    frame = _Frame(triangles, axis)
    cp = np.repeat(np.arange(len(points)), t_n)
    ct = (np.repeat(point_face * t_n, t_n).reshape(-1, t_n) + np.arange(t_n)).reshape(-1)
    return frame.exact(points, cp, ct)


class AxisBins(_Frame):
    """Triangles of a batch binned for lines parallel to ``axis``.

    triangles : (B, T, 3, 3) float corner coordinates; axis : 0, 1 or 2; cell : bin size in the
    plane of the two other axes (about the triangles' size).
    """

    def __init__(self, triangles: np.ndarray, axis: int, cell: float) -> None:
        _Frame.__init__(self, triangles, axis)
        b_n, t_n = triangles.shape[:2]
        a, c, axis, tri = self.a, self.c, self.axis, self.tri

        lo_a, hi_a = _min3(tri[:, a]), _max3(tri[:, a])
        lo_c, hi_c = _min3(tri[:, c]), _max3(tri[:, c])
        self.org_a = lo_a.reshape(b_n, t_n).min(1)
        self.org_c = lo_c.reshape(b_n, t_n).min(1)
        tri_face = np.repeat(np.arange(b_n), t_n)
        self.inv = inv = 1.0 / cell
        ia0 = ((lo_a - self.org_a[tri_face]) * inv).astype(np.int64)
        ia1 = ((hi_a - self.org_a[tri_face]) * inv).astype(np.int64)
        ic0 = ((lo_c - self.org_c[tri_face]) * inv).astype(np.int64)
        ic1 = ((hi_c - self.org_c[tri_face]) * inv).astype(np.int64)
        self.n_a = int(ia1.max()) + 1 if ia1.size else 1
        self.n_c = int(ic1.max()) + 1 if ic1.size else 1
        self.n_cells = self.n_a * self.n_c
        keys, owner = self._cell_copies(tri_face, ia0, ia1, ic0, ic1)
        order = _argsort_keys(keys, b_n * self.n_cells)
        keys, self.tri_flat = keys[order], owner[order]
        new = np.empty(len(keys), dtype=bool)
        if len(keys):
            new[0] = True
            np.not_equal(keys[1:], keys[:-1], out=new[1:])
        first = np.flatnonzero(new)
        self.cell_keys = keys[first]
        self.bounds = np.append(first, len(keys))
        if len(keys):
            self.cell_lo = np.minimum.reduceat(_min3(tri[:, axis])[self.tri_flat], first)
            self.cell_hi = np.maximum.reduceat(_max3(tri[:, axis])[self.tri_flat], first)
        else:
            self.cell_lo = self.cell_hi = np.zeros(0)

    def _cell_copies(
        self,
        tri_face: np.ndarray,
        ia0: np.ndarray,
        ia1: np.ndarray,
        ic0: np.ndarray,
        ic1: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray]:
        """(key, triangle) for every cell each triangle's box covers.

        Boxes up to 3 × 3 cells (nearly all) go through a fixed 9-slot mask; bigger ones
        through a general expansion.
        """
        wa, wc = ia1 - ia0, ic1 - ic0
        base = tri_face * self.n_cells + ia0 * self.n_c + ic0
        is_small = (wa < 3) & (wc < 3)
        mask = (wa[:, None] >= _DA) & (wc[:, None] >= _DC) & is_small[:, None]
        rows, slot = np.nonzero(mask)
        keys = base[rows] + (_DA * self.n_c + _DC)[slot]
        owner = rows
        big = np.flatnonzero(~is_small)
        if len(big):
            wa_b, wc_b = wa[big] + 1, wc[big] + 1
            counts = wa_b * wc_b
            o = np.repeat(np.arange(len(big)), counts)
            k = _ranges(np.zeros(len(big), dtype=np.int64), counts)
            keys = np.concatenate([keys, base[big][o] + (k // wc_b[o]) * self.n_c + k % wc_b[o]])
            owner = np.concatenate([owner, big[o]])
        return keys, owner

    def hits(
        self, points: np.ndarray, point_face: np.ndarray, need: np.ndarray | int | None = None
    ) -> LineHits:
        """Crossings of the lines through ``points`` (Q, 3) of batch rows ``point_face`` (Q,).

        need : None (every hit), or (Q,) / scalar int — which hits the caller needs: 0, surfaces
        on both sides of the point; +1, some on its + side; −1, some on its − side; 2, some on
        either side. A point whose cell's span along the axis cannot give that is skipped (no
        hits returned for it).
        """
        a, c, axis = self.a, self.c, self.axis
        ja = np.floor((points[:, a] - self.org_a[point_face]) * self.inv).astype(np.int64)
        jc = np.floor((points[:, c] - self.org_c[point_face]) * self.inv).astype(np.int64)
        ok = np.flatnonzero((ja >= 0) & (ja < self.n_a) & (jc >= 0) & (jc < self.n_c))
        if len(self.cell_keys) == 0:
            ok = ok[:0]
        key = point_face[ok] * self.n_cells + ja[ok] * self.n_c + jc[ok]
        slot = np.minimum(np.searchsorted(self.cell_keys, key), max(len(self.cell_keys) - 1, 0))
        keep = self.cell_keys[slot] == key
        if need is not None:
            pk = points[ok, axis]
            above = pk < self.cell_hi[slot]
            below = pk > self.cell_lo[slot]
            nd = np.broadcast_to(np.asarray(need), points.shape[:1])[ok]
            keep &= np.select(
                [nd == 1, nd == -1, nd == 0], [above, below, above & below], above | below
            )
        ok, slot = ok[keep], slot[keep]
        start = self.bounds[slot]
        n = self.bounds[slot + 1] - start
        return self.exact(points, np.repeat(ok, n), self.tri_flat[_ranges(start, n)])


BRUTE_PAIRS = 40_000  # below this many point–triangle pairs, testing all beats binning


def line_hits(
    points: np.ndarray,
    point_face: np.ndarray,
    triangles: np.ndarray,
    axis: int,
    cell: float,
    need: np.ndarray | int | None = None,
) -> LineHits:
    """Every hit of ``points`` against ``triangles`` (B, T, 3, 3) along ``axis``: by brute force
    for a few points (``need`` then only saves work, it is not applied), else binned
    (:class:`AxisBins`)."""
    if len(points) * triangles.shape[1] <= BRUTE_PAIRS:
        return brute_hits(points, point_face, triangles, axis)
    return AxisBins(triangles, axis, cell).hits(points, point_face, need)
