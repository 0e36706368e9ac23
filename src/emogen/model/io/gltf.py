"""One evaluated face out: a static GLB (for Blender/Unity) or an OBJ in the model's order.

The GLB has one primitive per material (:mod:`~emogen.model.io.gltf_layout`) and EmoGen's
asset metadata (:mod:`~emogen.model.io.gltf_asset`). The rig as a GLB with morph targets, for
the browser viewer, is :func:`emogen.render.model_glb.export_model_glb`; reading GLBs is
:func:`emogen.model.io.gltf_import.import_glb`.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from emogen.errors import ResourceError, ShapeError
from emogen.model.geometry import vertex_normals
from emogen.model.io.glb import GlbBuilder
from emogen.model.io.gltf_asset import (
    CM_TO_M,
    asset_header,
    materials,
    model_licence,
    write_file,
)
from emogen.model.io.gltf_layout import (
    export_layout,
    glb_primitive,
    select_polygons,
)
from emogen.model.io.obj import write_obj

if TYPE_CHECKING:
    from emogen.model.face import FaceModel

__all__ = ["export_face_glb", "export_face_obj"]


def _one_face(model: FaceModel, weights: np.ndarray, gaze: bool) -> np.ndarray:
    w = np.asarray(weights, dtype=np.float64)
    if w.shape != (model.n_shapes,):
        raise ShapeError(f"weights must have shape ({model.n_shapes},) (one face); got {w.shape}")
    return model.evaluate(w[None], gaze=gaze)[0]


def _weights_extras(model: FaceModel, weights: np.ndarray) -> dict[str, float]:
    return {
        s: float(x)
        for s, x in zip(model.shape_names, np.asarray(weights, dtype=np.float64), strict=True)
        if x != 0
    }


def export_face_glb(
    model: FaceModel,
    weights: np.ndarray,
    path: str | Path,
    *,
    parts: tuple[str, ...] | None = None,
    gaze: bool = True,
) -> None:
    """Write one evaluated face (weights (n_shapes,)) as a static float32 GLB for Blender/Unity."""
    path = Path(path)
    face = _one_face(model, weights, gaze).astype(np.float64)
    layout = export_layout(model, parts)
    u = layout.vertices
    verts = face[u]
    normals = vertex_normals(verts, layout.triangles).astype(np.float32)
    positions = (verts * CM_TO_M).astype(np.float32)
    b = GlbBuilder()
    prims: list[dict[str, Any]] = []
    for prim in layout.primitives:
        at = np.searchsorted(u, prim.source)
        attributes = {
            "POSITION": b.attribute(positions[at], min_max=True),
            "NORMAL": b.attribute(normals[at]),
        }
        prims.append(glb_primitive(b, model, layout, prim, len(prims), attributes))
    doc = {
        "asset": asset_header(
            model, layout, {"weights": _weights_extras(model, weights), "gaze_applied": gaze}
        ),
        "scene": 0,
        "scenes": [{"name": model.name, "nodes": [0]}],
        "nodes": [{"name": model.name, "mesh": 0}],
        "meshes": [{"name": model.name, "primitives": prims}],
        "materials": materials(model, layout),
    }
    write_file(path, b.finish(doc))


def export_face_obj(
    model: FaceModel,
    weights: np.ndarray,
    path: str | Path,
    *,
    parts: tuple[str, ...] | None = None,
    gaze: bool = True,
) -> None:
    """Write one evaluated face as OBJ in centimetres: every vertex in the model's order (so
    it lines up with ICT-FaceKit's own OBJs), UVs, and the original quads of ``parts`` grouped
    by ``usemtl``. The header names the model hash, the weights and the licence."""
    path = Path(path)
    face = _one_face(model, weights, gaze)
    poly_ids, _ = select_polygons(model, parts)
    copyright_line, licence = model_licence(model)
    named = _weights_extras(model, weights)
    header = [
        f"EmoGen face of model '{model.name}' (identity {model.identity_label}), centimetres",
        f"model_hash {model.model_hash}",
        "weights " + (" ".join(f"{k}={v:.6g}" for k, v in named.items()) or "(neutral)"),
        f"gaze {'applied' if gaze else 'not applied'}",
    ]
    if copyright_line:
        header.append(copyright_line)
    if licence:
        header += ["", *licence.strip().splitlines()]
    has_uv = len(model.uvs) > 0 and model.polygon_uvs.shape == model.polygons.shape
    try:
        write_obj(
            path,
            face,
            model.polygons[poly_ids],
            "\n".join(header),
            uvs=model.uvs if has_uv else None,
            polygon_uvs=model.polygon_uvs[poly_ids] if has_uv else None,
            polygon_material=model.polygon_material[poly_ids],
            materials=model.materials,
        )
    except OSError as exc:
        raise ResourceError(f"cannot write {path}: {exc.strerror}") from None
