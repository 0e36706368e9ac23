"""Axis-aligned ray casting against a face's triangles, compiled with numba.

The collision rays are axis-aligned (vertical and outward), so the line along axis k through a
point is a point in the plane of the two other axes. :func:`bin_triangles` bins one face's
triangles' bounding boxes in that plane on a uniform grid (a counting sort; each cell also keeps
the span of its triangles along the axis); :func:`probe` looks up a point's cell, skips the
point when that span cannot give the hits it needs, and tests it exactly (2-D barycentric
coordinates, float64) against the few triangles there, returning every crossing of the whole
line through the point, on both sides. The collision detector
(:func:`emogen.correct.collision.detect`) calls them face by face, anchor by anchor.

The per-face, per-ray loops are compiled by numba (``cache=True``: compiled once per machine,
then loaded from ``__pycache__``); numpy could only run them through large intermediate arrays,
several times slower (see docs/correctives.md).
"""

from __future__ import annotations

import numpy as np
from numba import njit

NO_FILTER = 3  # ``need`` code: every hit of the line, whatever the cell's span
MAX_CELLS = 1 << 20  # per face; a wider grid (a degenerate, huge face) gets coarser cells


@njit(cache=True, nogil=True)
def grow(arr: np.ndarray, size: int) -> np.ndarray:  # pragma: no cover - compiled
    """A copy of the rows of ``arr`` (N, C) with room for ``size`` rows."""
    out = np.empty((size, arr.shape[1]), dtype=arr.dtype)
    out[: len(arr)] = arr
    return out


@njit(cache=True, nogil=True)
def hit_buffers(
    n: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover
    """Scratch for :func:`probe`: triangle, t, facing, u, v of up to ``n`` hits."""
    return np.empty(n, dtype=np.int64), np.empty(n), np.empty(n), np.empty(n), np.empty(n)


@njit(cache=True, nogil=True)
def gather_triangles(
    vertices: np.ndarray, corners: np.ndarray, out: np.ndarray
) -> None:  # pragma: no cover - compiled
    """out (T, 3, 3) ← the corners (T, 3) of one face's vertices (V, 3)."""
    for t in range(corners.shape[0]):
        for k in range(3):
            for d in range(3):
                out[t, k, d] = vertices[corners[t, k], d]


@njit(cache=True, nogil=True)
def bin_triangles(
    tri: np.ndarray, axis: int, cell: float
) -> tuple[float, float, float, int, int, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """One face's triangles (T, 3, 3) binned for lines along ``axis``; compiled.

    Returns (org_a, org_c, inv, n_a, n_c, start, members, span_lo, span_hi): the grid's origin
    and inverse cell size in the plane (a, c) = (axis + 1, axis + 2) mod 3; cell k = i·n_c + j
    lists ``members[start[k]:start[k + 1]]`` (increasing triangle order) spanning
    [span_lo[k], span_hi[k]] along the axis. A face with non-finite corners gets no cells.
    """
    a = (axis + 1) % 3
    c = (axis + 2) % 3
    n_tris = tri.shape[0]
    org_a, org_c = np.inf, np.inf
    top_a, top_c = -np.inf, -np.inf
    finite = True
    for t in range(n_tris):
        for k in range(3):
            org_a = min(org_a, tri[t, k, a])
            org_c = min(org_c, tri[t, k, c])
            top_a = max(top_a, tri[t, k, a])
            top_c = max(top_c, tri[t, k, c])
            for d in range(3):
                finite = finite and np.isfinite(tri[t, k, d])
    return bin_triangles_in(tri, axis, cell, org_a, org_c, top_a, top_c, finite)


@njit(cache=True, nogil=True)
def bin_triangles_in(
    tri: np.ndarray,
    axis: int,
    cell: float,
    org_a: float,
    org_c: float,
    top_a: float,
    top_c: float,
    finite: bool,
) -> tuple[float, float, float, int, int, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`bin_triangles` with the triangles' extent in the plane already known (the
    smallest and largest corner coordinates along axis + 1 and axis + 2, and whether every
    corner is finite — the detector has them from the lower lip's vertices); compiled."""
    a = (axis + 1) % 3
    c = (axis + 2) % 3
    n_tris = tri.shape[0]
    if not (finite and n_tris > 0):
        empty = np.zeros(1, dtype=np.int64)
        return 0.0, 0.0, 1.0, 0, 0, empty, empty, np.zeros(0), np.zeros(0)
    size = cell
    while ((top_a - org_a) / size + 1.0) * ((top_c - org_c) / size + 1.0) > MAX_CELLS:
        size *= 2.0
    inv = 1.0 / size
    n_a = int((top_a - org_a) * inv) + 1
    n_c = int((top_c - org_c) * inv) + 1
    n_cells = n_a * n_c
    ia0 = np.empty(n_tris, dtype=np.int64)
    ia1 = np.empty(n_tris, dtype=np.int64)
    ic0 = np.empty(n_tris, dtype=np.int64)
    ic1 = np.empty(n_tris, dtype=np.int64)
    start = np.zeros(n_cells + 1, dtype=np.int64)
    for t in range(n_tris):
        ia0[t] = int((min(tri[t, 0, a], tri[t, 1, a], tri[t, 2, a]) - org_a) * inv)
        ia1[t] = min(int((max(tri[t, 0, a], tri[t, 1, a], tri[t, 2, a]) - org_a) * inv), n_a - 1)
        ic0[t] = int((min(tri[t, 0, c], tri[t, 1, c], tri[t, 2, c]) - org_c) * inv)
        ic1[t] = min(int((max(tri[t, 0, c], tri[t, 1, c], tri[t, 2, c]) - org_c) * inv), n_c - 1)
        for i in range(ia0[t], ia1[t] + 1):
            for j in range(ic0[t], ic1[t] + 1):
                start[i * n_c + j + 1] += 1
    for i in range(n_cells):
        start[i + 1] += start[i]
    fill = start[:-1].copy()
    members = np.empty(start[n_cells], dtype=np.int64)
    span_lo = np.full(n_cells, np.inf)
    span_hi = np.full(n_cells, -np.inf)
    for t in range(n_tris):  # increasing t: each cell lists its triangles in order
        lo_k = min(tri[t, 0, axis], tri[t, 1, axis], tri[t, 2, axis])
        hi_k = max(tri[t, 0, axis], tri[t, 1, axis], tri[t, 2, axis])
        for i in range(ia0[t], ia1[t] + 1):
            for j in range(ic0[t], ic1[t] + 1):
                key = i * n_c + j
                members[fill[key]] = t
                fill[key] += 1
                span_lo[key] = min(span_lo[key], lo_k)
                span_hi[key] = max(span_hi[key], hi_k)
    return org_a, org_c, inv, n_a, n_c, start, members, span_lo, span_hi


@njit(cache=True, nogil=True, inline="always")
def cell_of(
    grid: tuple[float, float, float, int, int, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    axis: int,
    point: np.ndarray,
    need: int,
) -> int:  # pragma: no cover - compiled
    """The grid cell of the line along ``axis`` through ``point``, or −1 when :func:`probe`
    would find nothing there: outside the grid, an empty cell, or a cell whose span along the
    axis cannot give what ``need`` asks for (see :func:`probe`). Cheap: most anchors stop here,
    so the detector calls it before :func:`cell_hits` (inlined, no call per anchor)."""
    a = (axis + 1) % 3
    c = (axis + 2) % 3
    org_a, org_c, inv, n_a, n_c, start, _members, span_lo, span_hi = grid
    pk = point[axis]
    fa = np.floor((point[a] - org_a) * inv)
    fc = np.floor((point[c] - org_c) * inv)
    if not (fa >= 0 and fa < n_a and fc >= 0 and fc < n_c):
        return -1
    key = int(fa) * n_c + int(fc)
    if start[key] == start[key + 1]:
        return -1
    if need != NO_FILTER:
        above = pk < span_hi[key]
        below = pk > span_lo[key]
        if need == 1:
            ok = above
        elif need == -1:
            ok = below
        elif need == 0:
            ok = above and below
        else:
            ok = above or below
        if not ok:
            return -1
    return key


@njit(cache=True, nogil=True, inline="always")
def cell_hits(
    tri: np.ndarray,
    axis: int,
    grid: tuple[float, float, float, int, int, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    key: int,
    point: np.ndarray,
    hit_tri: np.ndarray,
    hit_t: np.ndarray,
    hit_facing: np.ndarray,
    hit_u: np.ndarray,
    hit_v: np.ndarray,
) -> int:  # pragma: no cover - compiled
    """The crossings of the line along ``axis`` through ``point`` with the triangles of grid
    cell ``key`` (from :func:`cell_of`), written to the ``hit_*`` buffers; their number."""
    a = (axis + 1) % 3
    c = (axis + 2) % 3
    start, members = grid[5], grid[6]
    pa, pc, pk = point[a], point[c], point[axis]
    n = 0
    for m in range(start[key], start[key + 1]):
        t = members[m]
        x0a, x0c, x0k = tri[t, 0, a], tri[t, 0, c], tri[t, 0, axis]
        ea_a = tri[t, 1, a] - x0a
        ea_c = tri[t, 1, c] - x0c
        eb_a = tri[t, 2, a] - x0a
        eb_c = tri[t, 2, c] - x0c
        det = ea_a * eb_c - ea_c * eb_a
        if det == 0.0:
            continue  # edge-on: no crossing
        inv_det = 1.0 / det
        dpa = pa - x0a
        dpc = pc - x0c
        u = (dpa * eb_c - dpc * eb_a) * inv_det
        v = (ea_a * dpc - ea_c * dpa) * inv_det
        if not (u >= 0.0 and v >= 0.0 and u + v <= 1.0):
            continue
        coord = x0k + u * (tri[t, 1, axis] - x0k) + v * (tri[t, 2, axis] - x0k)
        hit_tri[n] = t
        hit_t[n] = coord - pk
        hit_facing[n] = det
        hit_u[n] = u
        hit_v[n] = v
        n += 1
    return n


@njit(cache=True, nogil=True, inline="always")
def probe(
    tri: np.ndarray,
    axis: int,
    grid: tuple[float, float, float, int, int, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    point: np.ndarray,
    need: int,
    hit_tri: np.ndarray,
    hit_t: np.ndarray,
    hit_facing: np.ndarray,
    hit_u: np.ndarray,
    hit_v: np.ndarray,
) -> int:  # pragma: no cover - compiled
    """The crossings of the line along ``axis`` through ``point`` (3,) with one face's binned
    triangles, written to the ``hit_*`` buffers (at least the largest cell's size); returns
    their number (0 when the point's cell is empty, outside the grid, or its span cannot give
    what ``need`` asks for: 0, surfaces on both sides of the point; +1, some on its + side; −1,
    some on its − side; 2, some on either side; ``NO_FILTER``, every hit).

    Hits are (triangle, t = hit coordinate − point coordinate along the axis, facing = the
    triangle normal's component along the axis × twice its area — its sign says whether a ray
    going +axis enters (< 0) or leaves (> 0) the surface's inside — and the barycentric weights
    u, v of the triangle's 2nd and 3rd corners), in increasing triangle order."""
    key = cell_of(grid, axis, point, need)
    if key < 0:
        return 0
    return cell_hits(tri, axis, grid, key, point, hit_tri, hit_t, hit_facing, hit_u, hit_v)
