"""Which parts of a model a GLB holds, and how its vertices map back to the source model.

:func:`export_layout` splits the exported polygons into one :class:`Primitive` per material,
in glTF vertex numbering: a primitive lists its source vertices in source order first, then
the UV-seam copies. Each primitive's ``extras.emogen`` maps its vertices and triangles back to
the source model (``source_vertices``: runs ``[first, count]`` of source vertex indices, one
per glTF vertex; ``source_polygons``: runs ``[first, n_polygons, triangles_per_polygon]``), so
an exported GLB re-imports in the source's vertex order with its regions.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from emogen.errors import ShapeError
from emogen.model.regions import ICT_VISIBLE_PARTS

if TYPE_CHECKING:
    from emogen.model.face import FaceModel
    from emogen.model.io.glb import GlbBuilder

__all__ = [
    "ExportLayout",
    "Primitive",
    "contained_regions",
    "export_layout",
    "glb_primitive",
    "primitive_extras",
    "primitive_regions",
    "primitive_uvs",
    "select_polygons",
]


def _triangle_corners(polygons: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Quads (a, b, c, d) → (a, b, c), (a, c, d): (owner polygon (T,), corner slots (T, 3))."""
    quads = np.flatnonzero(polygons[:, 3] >= 0)
    owner = np.concatenate([np.arange(len(polygons)), quads])
    slots = np.concatenate(
        [np.tile([0, 1, 2], (len(polygons), 1)), np.tile([0, 2, 3], (len(quads), 1))]
    )
    order = np.argsort(owner, kind="stable")
    return owner[order], slots[order]


def _runs(values: np.ndarray) -> list[list[int]]:
    """Runs of consecutive integers: [5, 6, 7, 2, 3] → [[5, 3], [2, 2]]."""
    if len(values) == 0:
        return []
    breaks = np.flatnonzero(np.diff(values) != 1) + 1
    starts = np.r_[0, breaks]
    counts = np.diff(np.r_[starts, len(values)])
    return [[int(values[s]), int(n)] for s, n in zip(starts, counts, strict=True)]


def _polygon_runs(tri_polygon: np.ndarray) -> list[list[int]]:
    """Triangle → source polygon as runs ``[first polygon, n polygons, triangles per polygon]``."""
    polys, counts = np.unique(tri_polygon, return_counts=True)
    if len(polys) == 0:
        return []
    breaks = np.flatnonzero((np.diff(polys) != 1) | (np.diff(counts) != 0)) + 1
    starts = np.r_[0, breaks]
    lengths = np.diff(np.r_[starts, len(polys)])
    return [[int(polys[s]), int(n), int(counts[s])] for s, n in zip(starts, lengths, strict=True)]


@dataclass(frozen=True)
class Primitive:
    """One material's part of the export, in glTF vertex numbering."""

    material: int  # index into model.materials
    source: np.ndarray  # (n,) source vertex of each glTF vertex
    uv: np.ndarray  # (n,) index into model.uvs (-1: none)
    triangles: np.ndarray  # (t, 3) indices into this primitive's vertices
    tri_polygon: np.ndarray  # (t,) source polygon of each triangle


@dataclass(frozen=True)
class ExportLayout:
    """The exported polygons and vertices of a model, and its primitives."""

    polygons: np.ndarray  # sorted source polygons exported
    vertices: np.ndarray  # sorted source vertices they use (U)
    triangles: np.ndarray  # (T, 3) triangles over U's numbering (for normals)
    primitives: tuple[Primitive, ...]
    parts: tuple[str, ...]


def select_polygons(
    model: FaceModel, parts: tuple[str, ...] | None
) -> tuple[np.ndarray, tuple[str, ...]]:
    if parts is None:
        if all(p in model.regions for p in ICT_VISIBLE_PARTS):
            parts = ICT_VISIBLE_PARTS
        else:
            return np.arange(len(model.polygons)), ()
    unknown = [p for p in parts if p not in model.regions]
    if unknown:
        raise ShapeError(
            f"parts names unknown region(s) {unknown}; regions are: {', '.join(model.regions)}"
        )
    ids = np.unique(
        np.concatenate(
            [np.arange(model.regions[p].p_start, model.regions[p].p_stop) for p in parts]
        )
    )
    if len(ids) == 0:
        raise ShapeError(f"parts {list(parts)} hold no polygons")
    return ids, tuple(parts)


def export_layout(model: FaceModel, parts: tuple[str, ...] | None) -> ExportLayout:
    poly_ids, parts = select_polygons(model, parts)
    owner, slots = _triangle_corners(model.polygons[poly_ids])
    tri_v = model.polygons[poly_ids][owner[:, None], slots]
    has_uv = len(model.uvs) > 0 and model.polygon_uvs.shape == model.polygons.shape
    tri_uv = (
        model.polygon_uvs[poly_ids][owner[:, None], slots] if has_uv else np.full_like(tri_v, -1)
    )
    tri_poly = poly_ids[owner]
    tri_mat = model.polygon_material[tri_poly]
    used = np.unique(tri_v)
    primitives = []
    for mat in np.unique(tri_mat):
        mask = tri_mat == mat
        corners = np.stack([tri_v[mask].reshape(-1), tri_uv[mask].reshape(-1)], 1)
        pairs, inverse = np.unique(corners, axis=0, return_inverse=True)
        primary = np.r_[True, pairs[1:, 0] != pairs[:-1, 0]]
        order = np.r_[np.flatnonzero(primary), np.flatnonzero(~primary)]
        new_index = np.empty(len(order), dtype=np.int64)
        new_index[order] = np.arange(len(order))
        primitives.append(
            Primitive(
                material=int(mat),
                source=pairs[order, 0],
                uv=pairs[order, 1],
                triangles=new_index[inverse.reshape(-1)].reshape(-1, 3),
                tri_polygon=tri_poly[mask],
            )
        )
    return ExportLayout(poly_ids, used, np.searchsorted(used, tri_v), tuple(primitives), parts)


def contained_regions(model: FaceModel, layout: ExportLayout) -> dict[str, list[Any]]:
    """Regions wholly exported, renumbered to the export's compacted vertex/polygon order."""
    out: dict[str, list[Any]] = {}
    u, p = layout.vertices, layout.polygons
    for r in model.regions.values():
        v0, v1 = np.searchsorted(u, [r.v_start, r.v_stop])
        p0, p1 = np.searchsorted(p, [r.p_start, r.p_stop])
        if r.v_stop > r.v_start and v1 - v0 == r.n_vertices and p1 - p0 == r.p_stop - r.p_start:
            out[r.name] = [int(v0), int(v1), int(p0), int(p1), r.group]
    return out


def primitive_regions(model: FaceModel, layout: ExportLayout, prim: Primitive) -> list[str]:
    return [
        p
        for p in layout.parts
        if np.any(
            (prim.tri_polygon >= model.regions[p].p_start)
            & (prim.tri_polygon < model.regions[p].p_stop)
        )
    ]


def primitive_extras(model: FaceModel, layout: ExportLayout, prim: Primitive) -> dict[str, Any]:
    regions = primitive_regions(model, layout, prim)
    return {
        "name": model.materials[prim.material] if prim.material < len(model.materials) else "",
        "emogen": {
            "regions": regions,
            "source_vertices": _runs(prim.source),
            "source_polygons": _polygon_runs(prim.tri_polygon),
        },
    }


def primitive_uvs(model: FaceModel, prim: Primitive) -> np.ndarray | None:
    if len(model.uvs) == 0 or np.all(prim.uv < 0):
        return None
    uv = model.uvs[np.maximum(prim.uv, 0)].astype(np.float32)
    uv[prim.uv < 0] = 0.0
    uv[:, 1] = 1.0 - uv[:, 1]  # OBJ's v points up, glTF's down
    return uv


def glb_primitive(
    b: GlbBuilder,
    model: FaceModel,
    layout: ExportLayout,
    prim: Primitive,
    material: int,
    attributes: dict[str, int],
    targets: Callable[[], list[dict[str, int]]] | None = None,
) -> dict[str, Any]:
    """The glTF primitive of ``prim``: its ``attributes`` plus the UVs, the morph ``targets``
    (made after the attributes), the indices, and its ``extras``. Adds them to ``b`` in that
    order, which fixes the GLB's byte layout."""
    uv = primitive_uvs(model, prim)
    if uv is not None:
        attributes["TEXCOORD_0"] = b.attribute(uv)
    made = targets() if targets is not None else []
    return {
        "attributes": attributes,
        "indices": b.indices(prim.triangles, len(prim.source)),
        "material": material,
        "mode": 4,
        **({"targets": made} if made else {}),
        "extras": primitive_extras(model, layout, prim),
    }
