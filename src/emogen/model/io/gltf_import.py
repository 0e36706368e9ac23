"""glTF in: a GLB (or glTF) whose meshes carry named morph targets, as a FaceModel.

Every triangle mesh of the default scene is read with its node's world transform; morph
targets are matched across meshes by the names in ``mesh.extras.targetNames`` (ARKit's
``jawOpen``, ``eyeBlinkLeft`` …, or ICT-FaceKit's ``_L``/``_R``). Quantized (normalized int8/int16,
uint8/uint16) and sparse accessors are decoded. glTF is in metres; the model comes out in
centimetres like ICT-FaceKit. A GLB written by :func:`~emogen.render.model_glb.export_model_glb`
comes back in its source's vertex order with quads and named regions, from its extras.
"""

from __future__ import annotations

import logging
import os
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from emogen.errors import ConfigError, ModelFileError
from emogen.model.face import FaceModel, from_arrays
from emogen.model.io.glb import Gltf, read_gltf
from emogen.model.io.ict import ModelArrays, model_content_hash
from emogen.model.io.obj import ObjTopology
from emogen.model.regions import Region
from emogen.model.rig import Rig
from emogen.model.rig_build import generic_rig, load_rig

log = logging.getLogger(__name__)
M_TO_CM = 100.0


class _NotRestorable(Exception):
    """The emogen extras do not match the geometry: fall back to the generic reading."""


@dataclass
class _Block:
    """Vertices of one POSITION accessor under one node: positions (n, 3), deltas (S, n, 3) cm."""

    positions: np.ndarray
    deltas: np.ndarray
    uvs: np.ndarray | None  # (n, 2), OBJ convention (v up)


@dataclass
class _Prim:
    block: int
    triangles: np.ndarray  # (t, 3) into the block
    material: str
    name: str
    extras: dict[str, Any]


def _local_matrix(node: dict[str, Any]) -> np.ndarray:
    if "matrix" in node:
        return np.asarray(node["matrix"], dtype=np.float64).reshape(4, 4).T  # column-major
    x, y, z, w = (float(c) for c in node.get("rotation", (0.0, 0.0, 0.0, 1.0)))
    rot = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
    m = np.eye(4)
    m[:3, :3] = rot * np.asarray(node.get("scale", (1.0, 1.0, 1.0)), dtype=np.float64)
    m[:3, 3] = node.get("translation", (0.0, 0.0, 0.0))
    return m


def _mesh_nodes(doc: dict[str, Any]) -> list[tuple[int, int, np.ndarray]]:
    """(node, mesh, world matrix) for every mesh node of the default scene."""
    nodes = doc.get("nodes", [])
    if not nodes:
        return [(-1, i, np.eye(4)) for i in range(len(doc.get("meshes", [])))]
    scenes = doc.get("scenes", [])
    if scenes:
        roots = scenes[doc.get("scene", 0)].get("nodes", [])
    else:
        children = {c for n in nodes for c in n.get("children", [])}
        roots = [i for i in range(len(nodes)) if i not in children]
    out: list[tuple[int, int, np.ndarray]] = []
    stack = [(int(r), np.eye(4)) for r in reversed(roots)]
    seen: set[int] = set()
    while stack:
        i, parent = stack.pop()
        if i in seen:
            raise ValueError(f"node {i} appears twice in the scene graph")
        seen.add(i)
        world = parent @ _local_matrix(nodes[i])
        if "mesh" in nodes[i]:
            out.append((i, int(nodes[i]["mesh"]), world))
        stack.extend((int(c), world) for c in reversed(nodes[i].get("children", [])))
    return out


def _target_names(mesh: dict[str, Any], index: int) -> list[str]:
    prims = mesh.get("primitives", [])
    n = max((len(p.get("targets", [])) for p in prims), default=0)
    names = (mesh.get("extras") or {}).get("targetNames")
    if names is None and prims:
        names = (prims[0].get("extras") or {}).get("targetNames")
    if n == 0:
        return []
    label = mesh.get("name") or f"mesh {index}"
    if not isinstance(names, list) or len(names) != n or not all(isinstance(s, str) for s in names):
        raise ModelFileError(
            f"{label} has {n} morph targets but no matching extras.targetNames list"
        )
    if len(set(names)) != len(names):
        raise ModelFileError(f"{label}: extras.targetNames repeats a name")
    return names


def _triangles(g: Gltf, prim: dict[str, Any], n: int) -> np.ndarray:
    idx = g.accessor(prim["indices"])[:, 0].astype(np.int64) if "indices" in prim else np.arange(n)
    mode = prim.get("mode", 4)
    if mode == 4:
        tri = idx[: len(idx) // 3 * 3].reshape(-1, 3)
    elif mode == 5:  # strip: every other triangle flips to keep the winding
        k = np.arange(max(len(idx) - 2, 0))
        tri = np.stack([idx[k], idx[k + 1 + k % 2], idx[k + 2 - k % 2]], 1)
    else:  # 6, fan
        k = np.arange(1, max(len(idx) - 1, 1))
        tri = np.stack([np.full(len(k), idx[0]), idx[k], idx[k + 1]], 1)
    if len(tri) and (tri.min() < 0 or tri.max() >= n):
        raise ValueError(f"indices refer to vertex {tri.max()}; the primitive has {n}")
    return tri


def _read_geometry(g: Gltf) -> tuple[list[str], list[_Block], list[_Prim]]:
    doc = g.doc
    meshes = doc.get("meshes", [])
    materials = doc.get("materials", [])
    names: list[str] = []
    mesh_names = {i: _target_names(m, i) for i, m in enumerate(meshes)}
    # EmoGen's own corrective targets (after the shapes) are not shapes of the model.
    emogen_extras = ((doc.get("asset") or {}).get("extras") or {}).get("emogen") or {}
    skip = set(emogen_extras.get("corrective_names") or ())
    for mesh_targets in mesh_names.values():
        names += [s for s in mesh_targets if s not in names and s not in skip]
    if not names:
        raise ModelFileError(
            "has no morph targets (blendshapes) with names in mesh.extras.targetNames"
        )
    index = {s: k for k, s in enumerate(names)}
    blocks: list[_Block] = []
    prims: list[_Prim] = []
    keys: dict[tuple[Any, ...], int] = {}
    for node, mesh_i, world in _mesh_nodes(doc):
        mesh = meshes[mesh_i]
        lin, shift = world[:3, :3], world[:3, 3]
        for j, prim in enumerate(mesh.get("primitives", [])):
            attrs = prim["attributes"]
            if prim.get("mode", 4) not in (4, 5, 6) or "POSITION" not in attrs:
                continue
            targets = prim.get("targets", [])
            key = (
                node,
                attrs["POSITION"],
                attrs.get("TEXCOORD_0"),
                tuple(t.get("POSITION") for t in targets),
            )
            if key not in keys:
                pos = g.accessor(attrs["POSITION"])[:, :3]
                deltas = np.zeros((len(names), len(pos), 3))
                for name, target in zip(mesh_names[mesh_i], targets, strict=True):
                    if "POSITION" in target and name in index:
                        deltas[index[name]] = (
                            g.accessor(target["POSITION"])[:, :3] @ lin.T * M_TO_CM
                        )
                uvs = None
                if "TEXCOORD_0" in attrs:
                    uvs = g.accessor(attrs["TEXCOORD_0"])[:, :2].astype(np.float64)
                    uvs[:, 1] = 1.0 - uvs[:, 1]
                keys[key] = len(blocks)
                blocks.append(_Block((pos @ lin.T + shift) * M_TO_CM, deltas, uvs))
            block = keys[key]
            mat = prim.get("material")
            mat_name = (
                "default" if mat is None else str(materials[mat].get("name") or f"material_{mat}")
            )
            extras = prim.get("extras") or {}
            label = (
                extras.get("name")
                if isinstance(extras.get("name"), str) and extras.get("name")
                else None
            )
            prims.append(
                _Prim(
                    block=block,
                    triangles=_triangles(g, prim, len(blocks[block].positions)),
                    material=mat_name,
                    name=label
                    or (
                        mat_name
                        if mat is not None
                        else f"{mesh.get('name') or f'mesh{mesh_i}'}_{j}"
                    ),
                    extras=extras,
                )
            )
    if not prims:
        raise ModelFileError("has no triangle mesh with POSITION data")
    return names, blocks, prims


def _unique_names(labels: list[str]) -> list[str]:
    seen: dict[str, int] = {}
    out = []
    for label in labels:
        seen[label] = seen.get(label, 0) + 1
        out.append(label if seen[label] == 1 else f"{label}_{seen[label]}")
    return out


def _generic(
    blocks: list[_Block], prims: list[_Prim]
) -> tuple[np.ndarray, np.ndarray, ObjTopology, dict[str, Region]]:
    """Blocks stacked in order; triangles as polygons; one region per primitive."""
    starts = np.cumsum([0] + [len(b.positions) for b in blocks])
    neutral = np.concatenate([b.positions for b in blocks])
    deltas = np.concatenate([b.deltas for b in blocks], axis=1)
    tris = [p.triangles + starts[p.block] for p in prims]
    polygons = np.concatenate([np.concatenate(tris), np.full((sum(map(len, tris)), 1), -1)], 1)
    if any(b.uvs is not None for b in blocks):
        uvs = np.concatenate(
            [b.uvs if b.uvs is not None else np.zeros((len(b.positions), 2)) for b in blocks]
        )
        polygon_uvs = polygons.copy()
    else:
        uvs, polygon_uvs = np.zeros((0, 2)), np.full_like(polygons, -1)
    materials = list(dict.fromkeys(p.material for p in prims))
    poly_mat = np.concatenate(
        [np.full(len(p.triangles), materials.index(p.material)) for p in prims]
    )
    regions = {}
    p0 = 0
    for name, p in zip(_unique_names([p.name for p in prims]), prims, strict=True):
        regions[name] = Region(
            name,
            int(starts[p.block]),
            int(starts[p.block + 1]),
            p0,
            p0 + len(p.triangles),
            "primitive",
        )
        p0 += len(p.triangles)
    topo = ObjTopology(
        polygons.astype(np.int32),
        polygon_uvs.astype(np.int32),
        uvs.astype(np.float32),
        poly_mat.astype(np.int16),
        tuple(materials),
    )
    return neutral, deltas, topo, regions


def _decode_runs(runs: Any) -> np.ndarray:
    return (
        np.concatenate([np.arange(int(a), int(a) + int(n)) for a, n in runs])
        if runs
        else np.zeros(0, np.int64)
    )


def _decode_polygon_runs(runs: Any) -> np.ndarray:
    parts = [np.repeat(np.arange(int(a), int(a) + int(n)), int(k)) for a, n, k in runs]
    return np.concatenate(parts) if parts else np.zeros(0, np.int64)


def _restored(
    blocks: list[_Block], prims: list[_Prim], extras: dict[str, Any]
) -> tuple[np.ndarray, np.ndarray, ObjTopology, dict[str, Region]]:
    """An EmoGen export back in its source's vertex order, with quads and regions."""
    sources, polys = [], []
    for p in prims:
        info = p.extras.get("emogen")
        if not isinstance(info, dict):
            raise _NotRestorable("a primitive has no emogen extras")
        sources.append(_decode_runs(info.get("source_vertices")))
        polys.append(_decode_polygon_runs(info.get("source_polygons")))
        if len(sources[-1]) != len(blocks[p.block].positions) or len(polys[-1]) != len(p.triangles):
            raise _NotRestorable("emogen extras do not match the primitive's size")
    u = np.unique(np.concatenate(sources))
    n_shapes = blocks[0].deltas.shape[0]
    neutral, deltas = np.zeros((len(u), 3)), np.zeros((n_shapes, len(u), 3))
    uv_rows, tri_v, tri_uv, uv_start = [], [], [], 0
    for p, src in zip(prims, sources, strict=True):
        b, at = blocks[p.block], np.searchsorted(u, src)
        neutral[at], deltas[:, at] = b.positions, b.deltas
        uv_rows.append(b.uvs if b.uvs is not None else np.zeros((len(src), 2)))
        tri_v.append(at[p.triangles])
        tri_uv.append(p.triangles + uv_start)
        uv_start += len(src)
    materials = list(dict.fromkeys(p.material for p in prims))
    tri_mat = np.concatenate(
        [np.full(len(p.triangles), materials.index(p.material)) for p in prims]
    )
    order = np.argsort(np.concatenate(polys), kind="stable")
    tv, tu, tm = np.concatenate(tri_v)[order], np.concatenate(tri_uv)[order], tri_mat[order]
    _, first, counts = np.unique(
        np.concatenate(polys)[order], return_index=True, return_counts=True
    )
    quad = counts == 2
    second = first[quad] + 1
    if counts.max(initial=1) > 2 or np.any(tv[second][:, :2] != tv[first[quad]][:, [0, 2]]):
        raise _NotRestorable("triangles do not pair into the recorded quads")
    polygons = np.full((len(first), 4), -1, dtype=np.int64)
    polygon_uvs = polygons.copy()
    polygons[:, :3], polygon_uvs[:, :3] = tv[first], tu[first]
    polygons[quad, 3], polygon_uvs[quad, 3] = tv[second, 2], tu[second, 2]
    regions = {}
    for name, spec in (extras.get("regions") or {}).items():
        v0, v1, p0, p1, group = spec
        if 0 <= v0 < v1 <= len(u) and 0 <= p0 <= p1 <= len(polygons):
            regions[name] = Region(name, v0, v1, p0, p1, group)
    if not regions:
        regions["all"] = Region("all", 0, len(u), 0, len(polygons))
    topo = ObjTopology(
        polygons.astype(np.int32),
        polygon_uvs.astype(np.int32),
        np.concatenate(uv_rows).astype(np.float32),
        tm[first].astype(np.int16),
        tuple(materials),
    )
    return neutral, deltas, topo, regions


def _rig_for(names: tuple[str, ...], regions: dict[str, Region], rig: Path | None) -> Rig:
    if rig is not None:
        return load_rig(names, rig)
    try:
        found = load_rig(names)  # the packaged ICT-FaceKit rig, when the names are ICT's
    except ConfigError:
        return generic_rig(names)
    if found.gaze is not None and not {found.gaze.left_eyeball, found.gaze.right_eyeball} <= set(
        regions
    ):
        found = replace(found, gaze=None)
    return found


def import_glb(
    path: str | os.PathLike[str], rig: str | os.PathLike[str] | None = None
) -> FaceModel:
    """Read a GLB/glTF with named morph targets as a FaceModel (centimetres).

    ``rig``: a rig TOML; by default the packaged ICT rig when the target names are ICT-FaceKit's,
    else :func:`~emogen.model.rig_build.generic_rig` (left/right twins paired).
    """
    path = Path(path)
    g = read_gltf(path)
    try:
        names, blocks, prims = _read_geometry(g)
        extras = ((g.doc.get("asset") or {}).get("extras") or {}).get("emogen") or {}
        try:
            if not extras:
                raise _NotRestorable("no emogen extras")
            neutral, deltas, topo, regions = _restored(blocks, prims, extras)
        except _NotRestorable as why:
            if extras:
                log.warning("%s: emogen extras ignored (%s); reading it as a plain GLB", path, why)
            neutral, deltas, topo, regions = _generic(blocks, prims)
    except ModelFileError as exc:
        raise ModelFileError(f"{path}: {exc}") from None
    except (KeyError, IndexError, TypeError, ValueError, AttributeError) as exc:
        raise ModelFileError(f"{path}: malformed glTF ({type(exc).__name__}: {exc})") from None
    shape_names = tuple(names)
    name = str(extras.get("model_name") or path.stem)
    neutral32, deltas32 = neutral.astype(np.float32), deltas.astype(np.float32)
    arrays = ModelArrays(
        name=name,
        neutral=neutral32,
        shape_names=shape_names,
        deltas=deltas32,
        identity_names=(),
        identity_deltas=np.zeros((0, len(neutral32), 3), dtype=np.float32),
        topology=topo,
        source_hash=g.digest,
        model_hash=model_content_hash(name, shape_names, neutral32, deltas32),
    )
    model = from_arrays(
        arrays, _rig_for(shape_names, regions, Path(rig) if rig else None), regions, str(path)
    )
    label = extras.get("identity")
    return replace(model, identity_label=label) if isinstance(label, str) and label else model
