"""The mouth's regions of interest: upper lip, lower lip and upper front teeth.

Everything here is topology plus the generic neutral, so the result holds for every identity.

* The **mouth line** is the boundary loop of the ``face`` region nearest the upper front
  teeth: ICT's face mesh stops at the inner lip line, where the ``mouth_socket`` lining is
  stitched on. Its two points of extreme x are the mouth corners; they split the loop into the
  **upper chain** (the one with the higher mean y) and the **lower chain**.
* Distances are **geodesic** (Dijkstra over the edges of the face and mouth-socket triangles),
  so they go round the mouth opening, never across it: a point of the upper lip is near the
  upper chain and far from the lower one, except at the corners, where both chains meet.
* ``side`` ∈ [−1, 1] says which lip a vertex belongs to: (d_lower − d_upper) / ``CORNER_RAMP``,
  clipped: +1 on the upper lip, −1 on the lower lip, passing smoothly through 0 at the corners.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from emogen.errors import ModelFileError
from emogen.model.io.obj import triangulate

UPPER_FRONT_TEETH = (
    "tooth_upper_right_canine",
    "tooth_upper_right_incisor_lateral",
    "tooth_upper_right_incisor_central",
    "tooth_upper_left_incisor_central",
    "tooth_upper_left_incisor_lateral",
    "tooth_upper_left_canine",
)
LIP_MESH_REGIONS = ("face", "mouth_socket")
CORNER_RAMP = 0.3  # cm: width of the upper/lower transition at the mouth corners


@dataclass(frozen=True)
class MouthGeometry:
    """Geodesic layout of the lips (arrays over all vertices; inf off the lip mesh).

    loop : (L,) int, the mouth line in order; upper, lower : int arrays, its two chains
    d_upper, d_lower : (V,) float, geodesic distance to the chains (cm)
    side : (V,) float in [−1, 1], +1 upper lip, −1 lower lip
    half_width : float, half the distance between the mouth corners (cm)
    centre_x : float, x of the mouth's centre
    lip_triangles : (T, 3) int, the triangles of the face and mouth socket
    """

    loop: np.ndarray
    upper: np.ndarray
    lower: np.ndarray
    d_upper: np.ndarray
    d_lower: np.ndarray
    side: np.ndarray
    half_width: float
    centre_x: float
    lip_triangles: np.ndarray


def region_triangles(polygons: np.ndarray, regions: dict, names: tuple[str, ...]) -> np.ndarray:
    """The triangles of the polygons of the named regions, (T, 3) int."""
    tris, owner = triangulate(polygons)
    keep = np.zeros(len(tris), dtype=bool)
    for name in names:
        if name not in regions:
            raise ModelFileError(
                f"the collision correctives need region '{name}'; the model has none"
            )
        r = regions[name]
        keep |= (owner >= r.p_start) & (owner < r.p_stop)
    return tris[keep]


def polygon_edges(polygons: np.ndarray) -> np.ndarray:
    """Directed edges (E, 2) of quads and triangles (-1 pads a triangle's 4th corner)."""
    nxt = np.roll(polygons, -1, axis=1)
    tri = polygons[:, 3] < 0
    nxt[tri, 2] = polygons[tri, 0]  # a triangle's third edge closes back to its first corner
    edges = np.stack([polygons, nxt], axis=-1).reshape(-1, 2)
    return edges[(edges >= 0).all(1)]


def boundary_loops(polygons: np.ndarray) -> list[np.ndarray]:
    """Closed loops of boundary edges (edges of one polygon only), each an ordered vertex array."""
    edges = polygon_edges(polygons)
    _, inverse, counts = np.unique(
        np.sort(edges, axis=1), axis=0, return_inverse=True, return_counts=True
    )
    border = edges[counts[inverse.reshape(-1)] == 1]
    following = dict(zip(border[:, 0].tolist(), border[:, 1].tolist(), strict=True))
    loops: list[np.ndarray] = []
    seen: set[int] = set()
    for start in following:
        if start in seen:
            continue
        loop = [start]
        seen.add(start)
        v = following[start]
        while v != start and v in following and v not in seen:
            loop.append(v)
            seen.add(v)
            v = following[v]
        loops.append(np.array(loop))
    return loops


def geodesic(vertices: np.ndarray, triangles: np.ndarray, sources: np.ndarray) -> np.ndarray:
    """Shortest edge-path distance from the nearest source to every vertex (inf if unreachable)."""
    e = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    length = np.linalg.norm(vertices[e[:, 0]] - vertices[e[:, 1]], axis=1)
    n = len(vertices)
    graph = coo_matrix((length, (e[:, 0], e[:, 1])), shape=(n, n)).tocsr()
    return dijkstra(graph, directed=False, indices=sources, min_only=True)


def mouth_geometry(neutral: np.ndarray, polygons: np.ndarray, regions: dict) -> MouthGeometry:
    """Find the mouth line and the geodesic layout of the lips (see the module docstring)."""
    neutral = np.asarray(neutral, dtype=np.float64)
    face = regions["face"]
    loops = boundary_loops(polygons[face.polygons])
    teeth = np.concatenate(
        [np.arange(regions[t].v_start, regions[t].v_stop) for t in UPPER_FRONT_TEETH]
    )
    target = neutral[teeth].mean(0)
    loop = min(loops, key=lambda lp: float(np.linalg.norm(neutral[lp].mean(0) - target)))
    x = neutral[loop, 0]
    i0, i1 = sorted((int(np.argmin(x)), int(np.argmax(x))))
    part_a = loop[i0 : i1 + 1]
    part_b = np.r_[loop[i1:], loop[: i0 + 1]]
    upper, lower = (
        (part_a, part_b)
        if neutral[part_a, 1].mean() > neutral[part_b, 1].mean()
        else (part_b, part_a)
    )
    tris = region_triangles(polygons, regions, LIP_MESH_REGIONS)
    d_up = geodesic(neutral, tris, upper[1:-1])
    d_lo = geodesic(neutral, tris, lower[1:-1])
    reached = np.isfinite(d_up) & np.isfinite(d_lo)
    side = np.zeros(len(neutral))
    side[reached] = np.clip((d_lo[reached] - d_up[reached]) / CORNER_RAMP, -1.0, 1.0)
    corners = neutral[[loop[i0], loop[i1]]]
    return MouthGeometry(
        loop=loop,
        upper=upper,
        lower=lower,
        d_upper=d_up,
        d_lower=d_lo,
        side=side,
        half_width=float(abs(corners[1, 0] - corners[0, 0]) / 2),
        centre_x=float(corners[:, 0].mean()),
        lip_triangles=tris,
    )
