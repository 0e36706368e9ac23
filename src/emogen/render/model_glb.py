"""The rig as a GLB with morph targets, for the browser viewer (and any glTF viewer).

The model GLB holds one mesh, one primitive per material
(:mod:`~emogen.model.io.gltf_layout`); every primitive has a morph target per shape (POSITION
and NORMAL deltas) in the model's shape order, then one per corrective
(:func:`~emogen.correct.faces.model_correctives`: combinational then collision;
``asset.extras.emogen.corrective_names``), and ``mesh.extras.targetNames`` names them all, so
three.js drives every primitive with the same weight vector through ``morphTargetDictionary``.
The targets are sparse (only vertices that move) and quantized
(:mod:`~emogen.render.morph_targets`). glTF is in metres; the node scales by 0.01.

With ``textures`` (an identity's :class:`~emogen.appearance.textures.SkinTextures`) the GLB
embeds the skin atlas and the detail tile as WebP images (``EXT_texture_webp``), records their
texture indices, the appearance and the fitted camera in ``asset.extras.emogen``
(``textures``, ``appearance``, ``camera``), and the skin materials show the atlas as their
base colour (``KHR_texture_transform`` maps the UDIM ``u`` in tiles to the atlas) for viewers
that show the GLB as is; EmoGen's viewer samples both images itself, as shade.glsl does.
"""

from __future__ import annotations

import gzip
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from emogen.model.io.glb import GlbBuilder
from emogen.model.io.gltf_asset import asset_header, gaze_extras, materials, write_file
from emogen.model.io.gltf_layout import (
    ExportLayout,
    export_layout,
    glb_primitive,
    primitive_regions,
)
from emogen.render.morph_targets import (
    CORRECTIVE_NORMAL_TOLERANCE,
    CORRECTIVE_TOLERANCE_CM,
    EncodedTargets,
    MorphTargets,
    float32,
    max_errors,
    morph_targets,
    quantized,
)

if TYPE_CHECKING:
    from emogen.appearance.textures import SkinTextures
    from emogen.model.face import FaceModel
    from emogen.render.look import Camera

__all__ = [
    "CORRECTIVE_NORMAL_TOLERANCE",
    "CORRECTIVE_TOLERANCE_CM",
    "SKIN_REGIONS",
    "ExportReport",
    "export_model_glb",
]

#: Regions whose materials carry the skin atlas: the regions of look.json's ``skin`` part
#: (tests/model/test_gltf.py checks they agree).
SKIN_REGIONS = ("face", "head_neck")
# Texture sampling as the offscreen renderer (emogen.render.gl.GLRenderer.set_textures).
_LINEAR, _LINEAR_MIPMAP_LINEAR, _CLAMP, _REPEAT = 9729, 9987, 33071, 10497


@dataclass(frozen=True)
class ExportReport:
    """What :func:`export_model_glb` wrote."""

    path: Path
    raw_bytes: int
    gzip_bytes: int  # gzip -9: what a server sends with Content-Encoding: gzip
    n_vertices: int  # glTF vertices over all primitives (UV seams and part borders duplicate)
    n_source_vertices: int
    n_triangles: int
    n_primitives: int
    n_shapes: int  # shape morph targets (then ``n_correctives`` corrective targets)
    quantized: bool
    position_step_cm: float  # quantization step (0 when float)
    max_position_error_cm: float  # over the neutral and every one-hot shape and corrective
    normals_clamped: int  # normal-delta components clamped to int8's [-1, 1]
    source_vertices: np.ndarray = field(repr=False)  # exported source vertices, sorted (U)
    corrective_names: tuple[str, ...] = ()  # corrective targets, after the shapes
    corrective_tolerance_cm: float = 0.0  # smaller corrective movements left out
    max_corrective_error_cm: float = 0.0  # over every one-hot corrective (tolerance included)

    @property
    def n_correctives(self) -> int:
        return len(self.corrective_names)

    @property
    def n_targets(self) -> int:
        return self.n_shapes + self.n_correctives

    def max_error_bound_cm(self, weights: np.ndarray) -> float:
        """Bound on |GLB face − model face| for weights (n_faces, n_shapes) or (n_faces,
        n_targets) (shapes then corrective weights), per vertex."""
        a = np.abs(np.atleast_2d(np.asarray(weights, dtype=np.float64)))
        w = a.sum(1).max()
        wc = a[:, self.n_shapes :].sum(1).max(initial=0.0)
        return (
            float(
                self.position_step_cm / 2 * np.sqrt(3) * (1 + w) + self.corrective_tolerance_cm * wc
            )
            + 1e-5
        )

    def __str__(self) -> str:
        err = (
            f"max position error {self.max_position_error_cm:.5f} cm"
            if self.quantized
            else "float32"
        )
        return (
            f"{self.raw_bytes / 1e6:.2f} MB ({self.gzip_bytes / 1e6:.2f} MB gzipped); "
            f"{self.n_vertices:,} vertices in {self.n_primitives} primitives, {self.n_triangles:,} "
            f"triangles, {self.n_shapes} shape + {self.n_correctives} corrective morph targets; "
            f"{err}"
        )


def export_model_glb(
    model: FaceModel,
    path: str | Path,
    *,
    parts: tuple[str, ...] | None = None,
    quantize: bool = True,
    correctives: bool = True,
    corrective_tolerance_cm: float = CORRECTIVE_TOLERANCE_CM,
    corrective_normal_tolerance: float = CORRECTIVE_NORMAL_TOLERANCE,
    corrective_normals: bool = False,
    textures: SkinTextures | None = None,
    camera: Camera | None = None,
) -> ExportReport:
    """Write the model as a GLB with one morph target per shape (positions and normals).

    parts : regions to export; default ICT-FaceKit's visible parts (``ICT_VISIBLE_PARTS``),
    or the whole mesh for a model without them. ``quantize``: int16 positions and deltas,
    int8 normals (KHR_mesh_quantization); float32 otherwise (sparse morph targets in both).
    ``correctives``: after the shapes, one target per corrective of the model
    (:func:`~emogen.correct.faces.model_correctives`: combinational then collision, named in
    ``asset.extras.emogen.corrective_names``), so a viewer shows corrected faces from the full
    vector of :meth:`~emogen.correct.apply.CorrectionResult.columns` (effective weights, then
    corrective weights). Corrective targets leave out vertices moved less than
    ``corrective_tolerance_cm`` and are rounded to about that step; their NORMAL deltas are
    zero unless ``corrective_normals`` (then those under ``corrective_normal_tolerance``
    are left out), which keeps the ICT GLB under 3 MB gzipped.

    ``textures``: the identity's skin textures, embedded as WebP (``EXT_texture_webp``) and
    shown by the materials of :data:`SKIN_REGIONS`; ``asset.extras.emogen`` then records
    ``textures`` (texture indices ``skin``, ``detail``) and ``appearance``. ``camera``: the
    camera to view the face with (``asset.extras.emogen.camera``, centimetres). With both and
    ``hair = "long"`` in the textures' appearance, the identity's long-hair layer for that camera
    is embedded too (``asset.extras.emogen.hair_layer``: its image index).
    """
    path = Path(path)
    layout = export_layout(model, parts)
    targets = morph_targets(
        model,
        layout.vertices,
        layout.triangles,
        correctives=correctives,
        corrective_tolerance_cm=corrective_tolerance_cm,
        corrective_normal_tolerance=corrective_normal_tolerance,
        corrective_normals=corrective_normals,
    )
    enc = quantized(targets, corrective_tolerance_cm) if quantize else float32(targets)
    names = targets.corrective_names
    b = GlbBuilder()
    mesh: dict[str, Any] = {
        "name": model.name,
        "primitives": _primitives(b, model, layout, enc, quantize, targets.n_targets),
    }
    if model.n_shapes:
        mesh["weights"] = [0.0] * targets.n_targets
        mesh["extras"] = {"targetNames": [*model.shape_names, *names]}
    doc: dict[str, Any] = {
        "asset": asset_header(model, layout, _emogen_extras(model, names, enc, textures, camera)),
        "scene": 0,
        "scenes": [{"name": model.name, "nodes": [0]}],
        "nodes": [{"name": model.name, "mesh": 0, **enc.node}],
        "meshes": [mesh],
        "materials": materials(model, layout),
    }
    _declare_extensions(doc, b, model, layout, quantize, textures)
    if textures is not None and textures.appearance.hair == "long" and camera is not None:
        _add_hair_layer(doc, b, model, textures, camera)
    data = b.finish(doc)
    write_file(path, data)
    return _report(path, data, model, layout, targets, enc, quantize, corrective_tolerance_cm)


def _emogen_extras(
    model: FaceModel,
    corrective_names: tuple[str, ...],
    enc: EncodedTargets,
    textures: SkinTextures | None,
    camera: Camera | None,
) -> dict[str, Any]:
    """EmoGen's entries of ``asset.extras.emogen`` (before the textures' indices are added)."""
    gaze = gaze_extras(model)
    extras: dict[str, Any] = {
        "shape_names": list(model.shape_names),
        **({"corrective_names": list(corrective_names)} if corrective_names else {}),
        "position_step_cm": enc.step,
        **({"gaze": gaze} if gaze else {}),
        **({"camera": _camera_extras(camera)} if camera is not None else {}),
    }
    if textures is not None:
        extras["appearance"] = textures.appearance.record()
    return extras


def _report(
    path: Path,
    data: bytes,
    model: FaceModel,
    layout: ExportLayout,
    targets: MorphTargets,
    enc: EncodedTargets,
    quantize: bool,
    corrective_tolerance_cm: float,
) -> ExportReport:
    """What was written to ``path`` (``data``): sizes, counts and the encoding's errors."""
    max_err, max_corrective_err = max_errors(targets, enc)
    names = targets.corrective_names
    return ExportReport(
        path=path,
        raw_bytes=len(data),
        gzip_bytes=len(gzip.compress(data, compresslevel=9)),
        n_vertices=sum(len(p.source) for p in layout.primitives),
        n_source_vertices=len(layout.vertices),
        n_triangles=len(layout.triangles),
        n_primitives=len(layout.primitives),
        n_shapes=model.n_shapes,
        quantized=quantize,
        position_step_cm=enc.step,
        max_position_error_cm=max_err,
        normals_clamped=enc.clamped,
        source_vertices=layout.vertices,
        corrective_names=names,
        corrective_tolerance_cm=corrective_tolerance_cm if names else 0.0,
        max_corrective_error_cm=max_corrective_err,
    )


def _primitives(
    b: GlbBuilder,
    model: FaceModel,
    layout: ExportLayout,
    enc: EncodedTargets,
    quantize: bool,
    n_targets: int,
) -> list[dict[str, Any]]:
    """One glTF primitive per material, with its attributes and sparse morph targets."""
    prims: list[dict[str, Any]] = []
    for prim in layout.primitives:
        at = np.searchsorted(layout.vertices, prim.source)
        attributes = {
            "POSITION": b.attribute(enc.pos_base[at], normalized=quantize, min_max=True),
            "NORMAL": b.attribute(enc.nrm_base[at], normalized=quantize),
        }

        def targets(at: np.ndarray = at) -> list[dict[str, int]]:
            return [
                {
                    "POSITION": b.sparse(enc.pos_delta[k, at], normalized=quantize, min_max=True),
                    "NORMAL": b.sparse(enc.nrm_delta[k, at], normalized=quantize),
                }
                for k in range(n_targets)
            ]

        prims.append(glb_primitive(b, model, layout, prim, len(prims), attributes, targets))
    return prims


def _declare_extensions(
    doc: dict[str, Any],
    b: GlbBuilder,
    model: FaceModel,
    layout: ExportLayout,
    quantize: bool,
    textures: SkinTextures | None,
) -> None:
    """Embed the textures (if any) and list the extensions the document uses and requires."""
    required = ["KHR_mesh_quantization"] if quantize else []
    used = list(required)
    if textures is not None:
        skin = [
            k
            for k, prim in enumerate(layout.primitives)
            if set(primitive_regions(model, layout, prim)) & set(SKIN_REGIONS)
        ]
        doc["asset"]["extras"]["emogen"]["textures"] = _add_textures(doc, b, textures, skin)
        required.append("EXT_texture_webp")
        used += ["EXT_texture_webp", "KHR_texture_transform"]
    if used:
        doc["extensionsUsed"] = used
    if required:
        doc["extensionsRequired"] = required


def _add_hair_layer(
    doc: dict[str, Any], b: GlbBuilder, model: FaceModel, textures: SkinTextures, camera: Camera
) -> None:
    """Embed the identity's long-hair layer (:mod:`emogen.appearance.long_hair`, WebP) as an
    image the viewer lays over each face: ``asset.extras.emogen.hair_layer`` = its image index.
    No texture uses it (it is not drawn on the mesh)."""
    from emogen.appearance.long_hair import identity_layer, layer_webp

    data = layer_webp(identity_layer(model, textures.appearance, camera))
    doc["images"].append(
        {"name": "hair_layer", "bufferView": b.blob(data), "mimeType": "image/webp"}
    )
    doc["asset"]["extras"]["emogen"]["hair_layer"] = len(doc["images"]) - 1


def _camera_extras(camera: Camera) -> dict[str, Any]:
    return {
        "position_cm": [float(x) for x in camera.position],
        "target_cm": [float(x) for x in camera.target],
        "up": [float(x) for x in camera.up],
        "fov_y_deg": float(camera.fov_y_deg),
        "near_cm": float(camera.near),
        "far_cm": float(camera.far),
    }


def _add_textures(
    doc: dict[str, Any],
    b: GlbBuilder,
    textures: SkinTextures,
    skin_materials: list[int],
) -> dict[str, int]:
    """Embed the atlas and the detail tile (WebP) in ``doc``; the skin materials show the
    atlas. Returns the texture indices ``{"skin": i, "detail": j}``."""
    h, w = textures.albedo.shape[:2]
    tiles = w / h  # the atlas holds SKIN_TILES square UDIM tiles side by side
    doc["images"] = [
        {"name": name, "bufferView": b.blob(data), "mimeType": "image/webp"}
        for name, data in (("skin", textures.albedo_webp), ("detail", textures.detail_webp))
    ]
    doc["samplers"] = [
        {"magFilter": _LINEAR, "minFilter": _LINEAR_MIPMAP_LINEAR, "wrapS": wrap, "wrapT": wrap}
        for wrap in (_CLAMP, _REPEAT)
    ]
    doc["textures"] = [
        {"name": name, "sampler": k, "extensions": {"EXT_texture_webp": {"source": k}}}
        for k, name in enumerate(("skin", "detail"))
    ]
    for m in skin_materials:
        pbr = doc["materials"][m]["pbrMetallicRoughness"]
        pbr["baseColorFactor"] = [1.0, 1.0, 1.0, 1.0]
        pbr["baseColorTexture"] = {
            "index": 0,
            "extensions": {"KHR_texture_transform": {"scale": [1.0 / tiles, 1.0]}},
        }
    return {"skin": 0, "detail": 1}
