"""glTF out: the rig as a GLB with morph targets (for the browser), one face as GLB or OBJ.

The model GLB holds one mesh, one primitive per material; every primitive has a morph target
per shape (POSITION and NORMAL deltas) in the model's shape order, then one per corrective
(``model.correctives``: combinational then collision; ``asset.extras.emogen.corrective_names``),
and ``mesh.extras.targetNames`` names them all, so three.js drives every primitive with the same weight vector through
``morphTargetDictionary``. Positions and position deltas are int16 (KHR_mesh_quantization; the
node's scale and translation undo it), normals int8, morph targets sparse (only vertices that
move). glTF is in metres; EmoGen models are in centimetres (ICT-FaceKit's unit), so the node
scales by 0.01 and :func:`~emogen.model.io.gltf_import.import_glb` multiplies by 100.

Each primitive's ``extras.emogen`` maps its vertices and triangles back to the source model
(``source_vertices``: runs ``[first, count]`` of source vertex indices, one per glTF vertex;
``source_polygons``: runs ``[first, n_polygons, triangles_per_polygon]``), so an exported GLB
re-imports in the source's vertex order with its regions (``asset.extras.emogen.regions``).
UV seams duplicate vertices: a primitive lists its source vertices in source order first,
then the seam copies.

With ``textures`` (an identity's :class:`~emogen.appearance.textures.SkinTextures`) the GLB
embeds the skin atlas and the detail tile as WebP images (``EXT_texture_webp``), records their
texture indices, the appearance and the fitted camera in ``asset.extras.emogen``
(``textures``, ``appearance``, ``camera``), and the skin materials show the atlas as their
base colour (``KHR_texture_transform`` maps the UDIM ``u`` in tiles to the atlas) for viewers
that show the GLB as is; EmoGen's viewer samples both images itself, as shade.glsl does.
"""

from __future__ import annotations

import gzip
import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from scipy import sparse

from emogen.errors import ModelFileError, ShapeError
from emogen.model.io.glb import GlbBuilder, read_glb_json
from emogen.model.io.gltf_import import import_glb
from emogen.model.io.obj import write_obj
from emogen.model.regions import ICT_VISIBLE_PARTS

if TYPE_CHECKING:
    from emogen.appearance.textures import SkinTextures
    from emogen.model.face import FaceModel
    from emogen.render.look import Camera

__all__ = [
    "ICT_COPYRIGHT",
    "ExportReport",
    "export_face_glb",
    "export_face_obj",
    "export_model_glb",
    "import_glb",
    "vertex_normals",
]

log = logging.getLogger(__name__)

ICT_COPYRIGHT = "ICT-FaceKit © 2020 USC Institute for Creative Technologies, MIT licence"
EXTRAS_FORMAT = 1
CM_TO_M = 0.01
_Q16 = 32767  # int16 normalized: value = q / 32767
_Q8 = 127  # int8 normalized
#: Corrective targets leave out vertices moved less than this (cm) and round their deltas to
#: about this step; by default they carry no normal deltas (zero): with their own normals the
#: ICT GLB grows past 3 MB gzipped (3.03 MB even with a 4.5/127 normal tolerance), without them
#: it is 2.85 MB. A corrected face is then within this tolerance per unit corrective weight.
CORRECTIVE_TOLERANCE_CM = 0.01
CORRECTIVE_NORMAL_TOLERANCE = 4.5 / 127

# Plain PBR colours (sRGB) by material-name keyword, for viewers that show the GLB as is.
_COLOURS = (
    ("lash", (0.08, 0.06, 0.05)),
    ("iris", (0.32, 0.22, 0.14)),
    ("sclera", (0.93, 0.92, 0.89)),
    ("teeth", (0.92, 0.89, 0.80)),
    ("gum", (0.78, 0.40, 0.42)),
    ("tongue", (0.78, 0.40, 0.42)),
)
_SKIN = (0.82, 0.64, 0.55)
#: Regions whose materials carry the skin atlas: the regions of look.json's ``skin`` part
#: (tests/model/test_gltf.py checks they agree; the model layer does not read the look).
SKIN_REGIONS = ("face", "head_neck")
# Texture sampling as the offscreen renderer (emogen.render.gl.GLRenderer.set_textures).
_LINEAR, _LINEAR_MIPMAP_LINEAR, _CLAMP, _REPEAT = 9729, 9987, 33071, 10497


# ---- geometry -------------------------------------------------------------------------------
def vertex_normals(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals.

    vertices : (V, 3) or (B, V, 3); triangles : (T, 3) → normals of the same shape as
    ``vertices`` (float64; zero for vertices on no triangle of non-zero area).
    """
    v = np.asarray(vertices, dtype=np.float64)
    batch = v[None] if v.ndim == 2 else v
    n_v = batch.shape[1]
    tri = np.asarray(triangles, dtype=np.int64)
    a, b, c = (batch[:, tri[:, i]] for i in range(3))
    face = np.cross(b - a, c - a)  # (B, T, 3), length = twice the area
    incidence = sparse.csr_matrix(
        (np.ones(tri.size), (tri.reshape(-1), np.repeat(np.arange(len(tri)), 3))),
        shape=(n_v, len(tri)),
    )
    summed = incidence @ face.transpose(1, 0, 2).reshape(len(tri), -1)
    normals = np.asarray(summed).reshape(n_v, len(batch), 3).transpose(1, 0, 2)
    length = np.linalg.norm(normals, axis=-1, keepdims=True)
    normals = np.divide(normals, length, out=np.zeros_like(normals), where=length > 1e-20)
    return normals[0] if v.ndim == 2 else normals


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
class _Primitive:
    """One material's part of the export, in glTF vertex numbering."""

    material: int  # index into model.materials
    source: np.ndarray  # (n,) source vertex of each glTF vertex
    uv: np.ndarray  # (n,) index into model.uvs (-1: none)
    triangles: np.ndarray  # (t, 3) indices into this primitive's vertices
    tri_polygon: np.ndarray  # (t,) source polygon of each triangle


@dataclass(frozen=True)
class _Layout:
    polygons: np.ndarray  # sorted source polygons exported
    vertices: np.ndarray  # sorted source vertices they use (U)
    triangles: np.ndarray  # (T, 3) triangles over U's numbering (for normals)
    primitives: tuple[_Primitive, ...]
    parts: tuple[str, ...]


def _select_polygons(
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


def _layout(model: FaceModel, parts: tuple[str, ...] | None) -> _Layout:
    poly_ids, parts = _select_polygons(model, parts)
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
            _Primitive(
                material=int(mat),
                source=pairs[order, 0],
                uv=pairs[order, 1],
                triangles=new_index[inverse.reshape(-1)].reshape(-1, 3),
                tri_polygon=tri_poly[mask],
            )
        )
    return _Layout(poly_ids, used, np.searchsorted(used, tri_v), tuple(primitives), parts)


def _contained_regions(model: FaceModel, layout: _Layout) -> dict[str, list[Any]]:
    """Regions wholly exported, renumbered to the export's compacted vertex/polygon order."""
    out: dict[str, list[Any]] = {}
    u, p = layout.vertices, layout.polygons
    for r in model.regions.values():
        v0, v1 = np.searchsorted(u, [r.v_start, r.v_stop])
        p0, p1 = np.searchsorted(p, [r.p_start, r.p_stop])
        if r.v_stop > r.v_start and v1 - v0 == r.n_vertices and p1 - p0 == r.p_stop - r.p_start:
            out[r.name] = [int(v0), int(v1), int(p0), int(p1), r.group]
    return out


# ---- metadata -------------------------------------------------------------------------------
def model_licence(model: FaceModel) -> tuple[str | None, str | None]:
    """(copyright line, licence text) to carry with exports of ``model``."""
    src = Path(model.source) if model.source else None
    if src is not None and src.suffix.lower() in (".glb", ".gltf") and src.is_file():
        try:
            asset = read_glb_json(src).get("asset", {})
        except ModelFileError:
            asset = {}
        return asset.get("copyright"), (asset.get("extras") or {}).get("license")
    text = None
    for cand in (src.parent / "LICENSE", src / "LICENSE") if src is not None else ():
        if cand.is_file():
            text = cand.read_text(encoding="utf-8", errors="replace")
            break
    is_ict = model.name.startswith("ict-facekit") or (
        text is not None and "Institute for Creative Technologies" in text
    )
    return (ICT_COPYRIGHT if is_ict else None), text


def _sphere_centre(points: np.ndarray) -> np.ndarray:
    a = np.c_[2 * points, np.ones(len(points))]
    sol, *_ = np.linalg.lstsq(a, (points**2).sum(1), rcond=None)
    return sol[:3]


def _gaze_extras(model: FaceModel) -> dict[str, Any] | None:
    """What a viewer needs to turn the eyeballs (morph targets cannot): centres in metres."""
    gz = model.rig.gaze
    if gz is None or not {gz.left_eyeball, gz.right_eyeball} <= set(model.regions):
        return None
    centre = {
        side: [
            float(x) * CM_TO_M
            for x in _sphere_centre(model.neutral[model.regions[name].vertices].astype(np.float64))
        ]
        for side, name in (("left", gz.left_eyeball), ("right", gz.right_eyeball))
    }
    names = np.asarray(model.shape_names)
    return {
        "left_eyeball": gz.left_eyeball,
        "right_eyeball": gz.right_eyeball,
        "left_centre": centre["left"],
        "right_centre": centre["right"],
        **{
            k: names[getattr(gz, k)].tolist()
            for k in ("look_left", "look_right", "look_up", "look_down")
        },
        "yaw_deg": float(np.degrees(gz.yaw)),
        "pitch_up_deg": float(np.degrees(gz.pitch_up)),
        "pitch_down_deg": float(np.degrees(gz.pitch_down)),
        "rule": "yaw = yaw_deg * (mean(look_left) - mean(look_right)); pitch = pitch_up_deg * "
        "mean(look_up) - pitch_down_deg * mean(look_down); rotate each eyeball about its centre "
        "by yaw about +y then pitch about -x",
    }


def _asset(model: FaceModel, layout: _Layout, extra: dict[str, Any]) -> dict[str, Any]:
    from emogen import __version__

    copyright_line, licence = model_licence(model)
    emogen_extras: dict[str, Any] = {
        "format": EXTRAS_FORMAT,
        "model_name": model.name,
        "model_hash": model.model_hash,
        "identity": model.identity_label,
        "units": "metres in the file; EmoGen models are in centimetres",
        "source_vertex_count": model.n_vertices,
        "source_polygon_count": len(model.polygons),
        "parts": list(layout.parts),
        "regions": _contained_regions(model, layout),
        **extra,
    }
    asset: dict[str, Any] = {"version": "2.0", "generator": f"EmoGen {__version__}"}
    if copyright_line:
        asset["copyright"] = copyright_line
    asset["extras"] = {"emogen": emogen_extras, **({"license": licence} if licence else {})}
    return asset


def _materials(model: FaceModel, layout: _Layout) -> list[dict[str, Any]]:
    out = []
    for prim in layout.primitives:
        name = (
            model.materials[prim.material]
            if prim.material < len(model.materials)
            else f"material_{prim.material}"
        )
        srgb = next((c for key, c in _COLOURS if key in name.lower()), _SKIN)
        linear = [float(((x + 0.055) / 1.055) ** 2.4) for x in srgb]
        out.append(
            {
                "name": name,
                "pbrMetallicRoughness": {
                    "baseColorFactor": [*linear, 1.0],
                    "metallicFactor": 0.0,
                    "roughnessFactor": 0.6,
                },
                **({"doubleSided": True} if "lash" in name.lower() else {}),
            }
        )
    return out


def _primitive_regions(model: FaceModel, layout: _Layout, prim: _Primitive) -> list[str]:
    return [
        p
        for p in layout.parts
        if np.any(
            (prim.tri_polygon >= model.regions[p].p_start)
            & (prim.tri_polygon < model.regions[p].p_stop)
        )
    ]


def _primitive_extras(model: FaceModel, layout: _Layout, prim: _Primitive) -> dict[str, Any]:
    regions = _primitive_regions(model, layout, prim)
    return {
        "name": model.materials[prim.material] if prim.material < len(model.materials) else "",
        "emogen": {
            "regions": regions,
            "source_vertices": _runs(prim.source),
            "source_polygons": _polygon_runs(prim.tri_polygon),
        },
    }


def _uvs(model: FaceModel, prim: _Primitive) -> np.ndarray | None:
    if len(model.uvs) == 0 or np.all(prim.uv < 0):
        return None
    uv = model.uvs[np.maximum(prim.uv, 0)].astype(np.float32)
    uv[prim.uv < 0] = 0.0
    uv[:, 1] = 1.0 - uv[:, 1]  # OBJ's v points up, glTF's down
    return uv


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


def _write(path: Path, data: bytes) -> None:
    try:
        Path(path).write_bytes(data)
    except OSError as exc:
        raise ModelFileError(f"cannot write {path}: {exc.strerror}") from None


# ---- the model with morph targets ----------------------------------------------------------
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
    (``model.correctives``: combinational then collision, named in
    ``asset.extras.emogen.corrective_names``), so a viewer shows corrected faces from the full
    vector of :meth:`~emogen.correct.apply.CorrectionResult.columns` (effective weights, then
    corrective weights). Corrective targets leave out vertices moved less than
    ``corrective_tolerance_cm`` and are rounded to about that step; their NORMAL deltas are
    zero unless ``corrective_normals`` (then those under ``corrective_normal_tolerance``
    are left out), which keeps the ICT GLB under 3 MB gzipped.

    ``textures``: the identity's skin textures, embedded as WebP (``EXT_texture_webp``) and
    shown by the materials of :data:`SKIN_REGIONS`; ``asset.extras.emogen`` then records
    ``textures`` (texture indices ``skin``, ``detail``) and ``appearance``. ``camera``: the
    camera to view the face with (``asset.extras.emogen.camera``, centimetres).
    """
    path = Path(path)
    layout = _layout(model, parts)
    u = layout.vertices
    neutral = model.neutral[u].astype(np.float64)
    target_deltas = model.deltas[:, u].astype(np.float64)
    corrective_names: tuple[str, ...] = ()
    if correctives and model.n_shapes:
        c = model.correctives
        corrective_names = tuple(c.names)
        if corrective_names:
            target_deltas = np.concatenate(
                [
                    target_deltas,
                    c.combinational_deltas[:, u].astype(np.float64),
                    c.collision_deltas[:, u].astype(np.float64),
                ]
            )
    n_targets = model.n_shapes + len(corrective_names)
    shapes = neutral[None] + target_deltas  # (S + C, U, 3)
    normals0 = vertex_normals(neutral, layout.triangles)
    shape_normals = vertex_normals(shapes, layout.triangles)
    delta = shapes - neutral[None]
    dn_float = shape_normals - normals0[None]
    if corrective_names:
        # Corrective targets are sparser than the shapes (to keep the GLB small on the wire):
        # vertices a corrective moves less than the tolerance are left out of its target.
        cd, cn = delta[model.n_shapes :], dn_float[model.n_shapes :]
        cd[np.linalg.norm(cd, axis=-1) < corrective_tolerance_cm] = 0.0
        if corrective_normals:
            cn[np.abs(cn).max(axis=-1) < corrective_normal_tolerance] = 0.0
        else:
            cn[:] = 0.0
    if quantize:
        lo, hi = neutral.min(0), neutral.max(0)
        centre = (lo + hi) / 2
        half = float(max((hi - lo).max() / 2, np.abs(delta).max(initial=0.0), 1e-6))
        step = half / _Q16
        q0 = np.clip(np.rint((neutral - centre) / step), -_Q16, _Q16)
        # Deltas rounded on their own (not as differences of rounded shapes): a face's error
        # is then e0 + Σ w_k e_k with independent e_k, not amplified by Σ w_k.
        qd = np.rint(delta / step)
        if corrective_names:  # coarser steps (multiples of step): fewer distinct bytes to gzip
            f = max(1.0, float(np.floor(corrective_tolerance_cm / step)))
            qd[model.n_shapes :] = np.rint(delta[model.n_shapes :] / (f * step)) * f
        qd = np.clip(qd, -_Q16, _Q16)
        base_cm, delta_cm = centre + q0 * step, qd * step
        n0 = np.rint(normals0 * _Q8)
        dn = np.rint(dn_float * _Q8)
        clamped = int(np.count_nonzero(np.abs(dn) > _Q8))
        pos_base, pos_delta = q0.astype(np.int16), qd.astype(np.int16)
        nrm_base, nrm_delta = n0.astype(np.int8), np.clip(dn, -_Q8, _Q8).astype(np.int8)
        node = {"translation": [float(x) * CM_TO_M for x in centre], "scale": [half * CM_TO_M] * 3}
    else:
        tol = 1e-4  # cm (and unit-normal components): smaller changes are left out of the targets
        delta[np.all(np.abs(delta) < tol, axis=-1)] = 0.0
        dn = dn_float
        dn[np.all(np.abs(dn) < tol, axis=-1)] = 0.0
        pos_base, pos_delta = (
            (neutral * CM_TO_M).astype(np.float32),
            (delta * CM_TO_M).astype(np.float32),
        )
        nrm_base, nrm_delta = normals0.astype(np.float32), dn.astype(np.float32)
        base_cm, delta_cm = pos_base / CM_TO_M, pos_delta / CM_TO_M
        step, clamped, node = 0.0, 0, {}
    faces_cm = base_cm[None] + np.concatenate([np.zeros((1, len(u), 3)), delta_cm])
    errors = np.linalg.norm(faces_cm - np.concatenate([neutral[None], shapes]), axis=-1)
    max_err = float(errors[: model.n_shapes + 1].max())
    max_corrective_err = float(errors[model.n_shapes + 1 :].max(initial=0.0))
    b = GlbBuilder()
    prims: list[dict[str, Any]] = []
    for prim in layout.primitives:
        at = np.searchsorted(u, prim.source)
        attributes = {
            "POSITION": b.attribute(pos_base[at], normalized=quantize, min_max=True),
            "NORMAL": b.attribute(nrm_base[at], normalized=quantize),
        }
        uv = _uvs(model, prim)
        if uv is not None:
            attributes["TEXCOORD_0"] = b.attribute(uv)
        targets = [
            {
                "POSITION": b.sparse(pos_delta[k, at], normalized=quantize, min_max=True),
                "NORMAL": b.sparse(nrm_delta[k, at], normalized=quantize),
            }
            for k in range(n_targets)
        ]
        prims.append(
            {
                "attributes": attributes,
                "indices": b.indices(prim.triangles, len(prim.source)),
                "material": len(prims),
                "mode": 4,
                **({"targets": targets} if targets else {}),
                "extras": _primitive_extras(model, layout, prim),
            }
        )
    mesh: dict[str, Any] = {"name": model.name, "primitives": prims}
    if model.n_shapes:
        mesh["weights"] = [0.0] * n_targets
        mesh["extras"] = {"targetNames": [*model.shape_names, *corrective_names]}
    gaze = _gaze_extras(model)
    extras: dict[str, Any] = {
        "shape_names": list(model.shape_names),
        **({"corrective_names": list(corrective_names)} if corrective_names else {}),
        "position_step_cm": step,
        **({"gaze": gaze} if gaze else {}),
        **({"camera": _camera_extras(camera)} if camera is not None else {}),
    }
    if textures is not None:
        extras["appearance"] = textures.appearance.record()
    doc: dict[str, Any] = {
        "asset": _asset(model, layout, extras),
        "scene": 0,
        "scenes": [{"name": model.name, "nodes": [0]}],
        "nodes": [{"name": model.name, "mesh": 0, **node}],
        "meshes": [mesh],
        "materials": _materials(model, layout),
    }
    required = ["KHR_mesh_quantization"] if quantize else []
    used = list(required)
    if textures is not None:
        skin = [
            k
            for k, prim in enumerate(layout.primitives)
            if set(_primitive_regions(model, layout, prim)) & set(SKIN_REGIONS)
        ]
        doc["asset"]["extras"]["emogen"]["textures"] = _add_textures(doc, b, textures, skin)
        required.append("EXT_texture_webp")
        used += ["EXT_texture_webp", "KHR_texture_transform"]
    if used:
        doc["extensionsUsed"] = used
    if required:
        doc["extensionsRequired"] = required
    data = b.finish(doc)
    _write(path, data)
    return ExportReport(
        path=path,
        raw_bytes=len(data),
        gzip_bytes=len(gzip.compress(data, compresslevel=9)),
        n_vertices=sum(len(p.source) for p in layout.primitives),
        n_source_vertices=len(u),
        n_triangles=len(layout.triangles),
        n_primitives=len(layout.primitives),
        n_shapes=model.n_shapes,
        quantized=quantize,
        position_step_cm=step,
        max_position_error_cm=max_err,
        normals_clamped=clamped,
        source_vertices=u,
        corrective_names=corrective_names,
        corrective_tolerance_cm=corrective_tolerance_cm if corrective_names else 0.0,
        max_corrective_error_cm=max_corrective_err,
    )


# ---- one face -------------------------------------------------------------------------------
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
    layout = _layout(model, parts)
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
        uv = _uvs(model, prim)
        if uv is not None:
            attributes["TEXCOORD_0"] = b.attribute(uv)
        prims.append(
            {
                "attributes": attributes,
                "indices": b.indices(prim.triangles, len(prim.source)),
                "material": len(prims),
                "mode": 4,
                "extras": _primitive_extras(model, layout, prim),
            }
        )
    doc = {
        "asset": _asset(
            model, layout, {"weights": _weights_extras(model, weights), "gaze_applied": gaze}
        ),
        "scene": 0,
        "scenes": [{"name": model.name, "nodes": [0]}],
        "nodes": [{"name": model.name, "mesh": 0}],
        "meshes": [{"name": model.name, "primitives": prims}],
        "materials": _materials(model, layout),
    }
    _write(path, b.finish(doc))


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
    poly_ids, _ = _select_polygons(model, parts)
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
        raise ModelFileError(f"cannot write {path}: {exc.strerror}") from None
