"""glTF out and in: the real ICT-FaceKit model, the Khronos validator, GLBs built by pygltflib."""

from __future__ import annotations

import gzip
import json
import re
import shutil
import struct
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import pygltflib
import pytest

import emogen
from emogen.correct import correct_faces, evaluate_corrected, model_correctives
from emogen.errors import ModelFileError
from emogen.model.face import FaceModel
from emogen.model.geometry import vertex_normals
from emogen.model.io.glb import glb_bytes, read_gltf
from emogen.model.io.gltf import export_face_glb, export_face_obj
from emogen.model.io.gltf_asset import CM_TO_M, ICT_COPYRIGHT
from emogen.model.io.gltf_import import import_glb
from emogen.model.io.obj import parse_topology, parse_vertices
from emogen.model.regions import ICT_VISIBLE_PARTS
from emogen.model.rig_build import generic_rig
from emogen.render.model_glb import SKIN_REGIONS, ExportReport, export_model_glb

REPO = Path(__file__).resolve().parents[2]
ICT_DIR = REPO.parent / "shared" / "ict-facekit" / "FaceXModel"
VALIDATOR = REPO / "scripts" / "validate_gltf.mjs"
WIRE_LIMIT = 3_000_000  # bytes, gzip -9


# ---- fixtures and helpers -------------------------------------------------------------------
@pytest.fixture(scope="module")
def model() -> FaceModel:
    if not ICT_DIR.is_dir():
        pytest.fail(f"the ICT-FaceKit model must be at {ICT_DIR} (../shared beside the repository)")
    return emogen.load_model(ICT_DIR)


@pytest.fixture(scope="module")
def exported(
    model: FaceModel, tmp_path_factory: pytest.TempPathFactory
) -> tuple[Path, ExportReport]:
    path = tmp_path_factory.mktemp("glb") / "ict.glb"
    return path, export_model_glb(model, path)


@pytest.fixture(scope="module")
def reimported(exported: tuple[Path, ExportReport]) -> FaceModel:
    return import_glb(exported[0])


def validate(path: Path) -> dict[str, Any]:
    """The Khronos validator's report (npm gltf-validator through scripts/validate_gltf.mjs)."""
    if not (REPO / "node_modules" / "gltf-validator").is_dir():
        pytest.fail(f"the glTF validator is not installed: run `npm ci` in {REPO}")
    node = shutil.which("node")
    if node is None:
        pytest.fail("node is not on PATH: install Node.js (>= 18) to run the glTF validator")
    proc = subprocess.run(
        [node, str(VALIDATOR), str(path)], capture_output=True, text=True, cwd=REPO, timeout=300
    )
    if proc.returncode not in (0, 1):
        pytest.fail(f"the validator did not run: {proc.stderr}")
    report: dict[str, Any] = json.loads(proc.stdout)
    return report


def issues(report: dict[str, Any], severity: int) -> list[str]:
    return [
        f"{m['code']} at {m.get('pointer')}: {m['message']}"
        for m in report["issues"]["messages"]
        if m["severity"] == severity
    ]


def visible_vertices(model: FaceModel) -> np.ndarray:
    return np.unique(np.concatenate([model.regions[p].vertex_indices() for p in ICT_VISIBLE_PARTS]))


def visible_polygons(model: FaceModel) -> np.ndarray:
    return np.unique(
        np.concatenate(
            [
                np.arange(model.regions[p].p_start, model.regions[p].p_stop)
                for p in ICT_VISIBLE_PARTS
            ]
        )
    )


def split_glb(data: bytes) -> tuple[dict[str, Any], bytes]:
    n_json = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20 : 20 + n_json])
    return doc, data[20 + n_json + 8 :]


# ---- the model GLB ----------------------------------------------------------------------------
def test_model_glb_passes_the_khronos_validator(exported: tuple[Path, ExportReport]) -> None:
    report = validate(exported[0])
    assert issues(report, 0) == []  # errors
    assert issues(report, 1) == []  # warnings
    assert "KHR_mesh_quantization" in report["info"]["extensionsUsed"]


def test_model_glb_is_small_on_the_wire(exported: tuple[Path, ExportReport]) -> None:
    path, report = exported
    data = path.read_bytes()
    assert report.raw_bytes == len(data)
    assert report.gzip_bytes == len(gzip.compress(data, compresslevel=9))
    assert report.gzip_bytes <= WIRE_LIMIT, str(report)


def test_model_glb_layout_for_threejs(
    model: FaceModel, exported: tuple[Path, ExportReport]
) -> None:
    path, report = exported
    gltf = pygltflib.GLTF2().load(str(path))  # an independent reader
    assert gltf is not None
    assert len(gltf.meshes) == 1
    mesh = gltf.meshes[0]
    names = [*model.shape_names, *model_correctives(model).names]
    assert report.corrective_names == model_correctives(model).names and report.n_correctives > 0
    assert mesh.extras["targetNames"] == names
    assert len(mesh.weights) == len(names) == report.n_targets
    assert (
        len(mesh.primitives)
        == report.n_primitives
        == len(set(model.polygon_material[visible_polygons(model)].tolist()))
    )
    for prim in mesh.primitives:
        assert prim.attributes.POSITION is not None and prim.attributes.NORMAL is not None
        assert prim.attributes.TEXCOORD_0 is not None
        assert len(prim.targets) == report.n_targets
        assert all(set(t) == {"POSITION", "NORMAL"} for t in prim.targets)  # pygltflib: dicts
    assert gltf.extensionsRequired == ["KHR_mesh_quantization"]
    assert all(v.byteOffset % 4 == 0 for v in gltf.bufferViews)
    assert gltf.asset.copyright == ICT_COPYRIGHT
    extras = gltf.asset.extras
    assert extras["license"] == (ICT_DIR.parent / "LICENSE").read_text()
    assert extras["emogen"]["model_hash"] == model.model_hash
    assert extras["emogen"]["gaze"]["left_eyeball"] == "eyeball_left"


def test_quantization_error_is_small(exported: tuple[Path, ExportReport]) -> None:
    report = exported[1]
    assert report.quantized
    assert report.max_position_error_cm <= 0.005
    assert report.position_step_cm < 0.001


def test_round_trip_matches_the_original_model(
    model: FaceModel, exported: tuple[Path, ExportReport], reimported: FaceModel
) -> None:
    report = exported[1]
    np.testing.assert_array_equal(report.source_vertices, visible_vertices(model))
    assert reimported.shape_names == model.shape_names
    assert reimported.n_vertices == len(report.source_vertices)
    rng = np.random.default_rng(7)
    one_hot = np.eye(model.n_shapes)[
        [0, model.shape_index("jawOpen"), model.shape_index("eyeBlink_L"), -1]
    ]
    for weights, limit in (
        (np.zeros((1, model.n_shapes)), report.max_position_error_cm),
        (one_hot, report.max_position_error_cm),
        (rng.uniform(0, 1, (4, model.n_shapes)), None),
        (rng.uniform(0, 0.3, (4, model.n_shapes)), None),
    ):
        want = model.evaluate(weights, gaze=False)[:, report.source_vertices]
        got = reimported.evaluate(weights, gaze=False)
        err = float(np.linalg.norm(got - want, axis=-1).max())
        assert err <= (limit + 1e-5 if limit is not None else report.max_error_bound_cm(weights)), (
            err
        )
        assert err <= 0.005


def test_corrective_targets_evaluate_to_the_corrected_face(
    model: FaceModel, exported: tuple[Path, ExportReport]
) -> None:
    """Shapes then correctives (the full vector) through the GLB's own morph deltas equal
    evaluate_corrected(model, w) within the quantization + corrective tolerance bound."""
    path, report = exported
    g = read_gltf(path)
    prims = g.doc["meshes"][0]["primitives"]
    scale = np.asarray(g.doc["nodes"][0]["scale"]) / CM_TO_M
    shift = np.asarray(g.doc["nodes"][0]["translation"]) / CM_TO_M
    u = report.source_vertices
    rng = np.random.default_rng(11)
    core = rng.uniform(0, 0.6, (6, model.n_shapes))
    core[:, model.shape_index("jawOpen")] = [0.0, 0.2, 0.5, 0.8, 1.0, 0.4]
    result = correct_faces(model, core)
    assert result.correctives.any()
    full = np.hstack([result.weights, result.correctives])
    assert full.shape[1] == report.n_targets
    want = evaluate_corrected(model, core, gaze=False)[:, u]
    bound = report.max_error_bound_cm(full)
    for prim in prims:
        runs = prim["extras"]["emogen"]["source_vertices"]
        src = np.concatenate([np.arange(a, a + n) for a, n in runs])
        at = np.searchsorted(u, src)
        base = g.accessor(prim["attributes"]["POSITION"])[:, :3].astype(np.float64)
        deltas = np.stack(
            [g.accessor(t["POSITION"])[:, :3].astype(np.float64) for t in prim["targets"]]
        )
        assert len(deltas) == report.n_targets
        got = (base[None] + np.einsum("fk,kvc->fvc", full, deltas)) * scale + shift
        err = np.linalg.norm(got - want[:, at], axis=-1).max()
        assert err <= bound, (err, bound)
    one_hot = np.eye(report.n_targets)[model.n_shapes :]
    assert report.max_corrective_error_cm <= report.max_error_bound_cm(one_hot)


def test_model_glb_without_correctives_has_shape_targets_only(
    model: FaceModel, tmp_path: Path
) -> None:
    report = export_model_glb(model, tmp_path / "plain.glb", correctives=False)
    assert report.n_targets == model.n_shapes and report.corrective_names == ()
    names = read_gltf(tmp_path / "plain.glb").doc["meshes"][0]["extras"]["targetNames"]
    assert names == list(model.shape_names)


def test_round_trip_restores_topology_regions_and_rig(
    model: FaceModel, exported: tuple[Path, ExportReport], reimported: FaceModel
) -> None:
    u = exported[1].source_vertices
    polys = model.polygons[visible_polygons(model)]
    renumbered = np.where(polys >= 0, np.searchsorted(u, polys), -1)
    np.testing.assert_array_equal(reimported.polygons, renumbered)  # quads come back
    corners = polys >= 0
    uv_want = model.uvs[model.polygon_uvs[visible_polygons(model)]][corners]
    np.testing.assert_allclose(reimported.uvs[reimported.polygon_uvs][corners], uv_want, atol=1e-6)
    assert set(ICT_VISIBLE_PARTS) <= set(reimported.regions)
    for name in ("face", "teeth", "eyeball_left", "iris_right", "narrow_face"):
        r = model.regions[name]
        got = reimported.regions[name]
        np.testing.assert_array_equal(u[got.vertices], np.arange(r.v_start, r.v_stop))
    assert reimported.rig.name == model.rig.name
    assert reimported.rig.gene_names() == model.rig.gene_names()
    assert reimported.rig.gaze is not None
    w = model.rig.weights_from_names({"eyeLookLeft": 1.0, "eyeLookUp": 0.5})[None]
    gazed = np.linalg.norm(reimported.evaluate(w) - model.evaluate(w)[:, u], axis=-1).max()
    assert gazed < 0.01  # the eyeball centres are refitted on quantized vertices
    assert reimported.name == model.name
    assert reimported.source == str(exported[0])


def test_load_model_reads_a_glb(exported: tuple[Path, ExportReport], reimported: FaceModel) -> None:
    loaded = emogen.load_model(exported[0])
    assert loaded.model_hash == reimported.model_hash
    assert loaded.shape_names == reimported.shape_names


def test_plain_reading_of_the_export_without_emogen_extras(
    model: FaceModel, exported: tuple[Path, ExportReport], tmp_path: Path
) -> None:
    """Without the source mapping the GLB still reads: primitives stacked, one region each."""
    doc, blob = split_glb(exported[0].read_bytes())
    mapping = [p["extras"]["emogen"]["source_vertices"] for p in doc["meshes"][0]["primitives"]]
    del doc["asset"]["extras"]["emogen"]
    plain = tmp_path / "plain.glb"
    plain.write_bytes(glb_bytes(doc, blob))
    m2 = import_glb(plain)
    source = np.concatenate(
        [np.concatenate([np.arange(a, a + n) for a, n in runs]) for runs in mapping]
    )
    assert m2.n_vertices == exported[1].n_vertices == len(source)
    assert len(m2.regions) == exported[1].n_primitives
    assert m2.rig.gaze is None  # ICT names, but no eyeball regions to turn
    # without EmoGen's extras the corrective targets read as further shapes (zero here)
    assert m2.shape_names == (*model.shape_names, *exported[1].corrective_names)
    w = np.random.default_rng(3).uniform(0, 0.5, (2, model.n_shapes))
    w2 = np.hstack([w, np.zeros((2, exported[1].n_correctives))])
    err = np.linalg.norm(m2.evaluate(w2) - model.evaluate(w, gaze=False)[:, source], axis=-1).max()
    assert err <= exported[1].max_error_bound_cm(w)


def test_vertex_normals_of_a_tetrahedron_corner() -> None:
    verts = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    tris = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    n = vertex_normals(verts, tris)
    np.testing.assert_allclose(n[0], -np.ones(3) / np.sqrt(3))
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0)
    batch = vertex_normals(np.stack([verts, verts * 2]), tris)
    np.testing.assert_allclose(batch[1], n)


# ---- single faces -----------------------------------------------------------------------------
def test_face_obj_holds_the_evaluated_face(model: FaceModel, tmp_path: Path) -> None:
    weights = model.rig.weights_from_names({"jawOpen": 0.4, "mouthSmile": 0.7, "eyeLookLeft": 0.5})
    path = tmp_path / "face.obj"
    export_face_obj(model, weights, path)
    np.testing.assert_allclose(parse_vertices(path), model.evaluate(weights[None])[0], atol=1e-5)
    topo = parse_topology(path, model.n_vertices)
    np.testing.assert_array_equal(topo.polygons, model.polygons[visible_polygons(model)])
    np.testing.assert_allclose(topo.uvs, model.uvs, atol=1e-6)
    text = path.read_text()
    assert model.model_hash in text
    assert "jawOpen=0.4" in text
    assert ICT_COPYRIGHT in text
    assert "Permission is hereby granted" in text


def test_face_glb_validates_and_holds_the_face(model: FaceModel, tmp_path: Path) -> None:
    weights = model.rig.weights_from_names({"browInnerUp": 1.0, "mouthFrown": 0.6})
    path = tmp_path / "face.glb"
    export_face_glb(model, weights, path)
    report = validate(path)
    assert issues(report, 0) == [] and issues(report, 1) == []
    g = read_gltf(path)
    face = model.evaluate(weights[None])[0]
    for prim in g.doc["meshes"][0]["primitives"]:
        source = np.concatenate(
            [np.arange(a, a + n) for a, n in prim["extras"]["emogen"]["source_vertices"]]
        )
        np.testing.assert_allclose(
            g.accessor(prim["attributes"]["POSITION"]) * 100, face[source], atol=1e-4
        )
    with pytest.raises(ModelFileError, match="no morph targets"):
        import_glb(path)


def test_face_export_checks_the_weights(model: FaceModel, tmp_path: Path) -> None:
    with pytest.raises(emogen.ShapeError, match=r"weights must have shape \(57,\)"):
        export_face_obj(model, np.zeros((1, model.n_shapes)), tmp_path / "x.obj")


# ---- a GLB from elsewhere: ARKit names, pygltflib, node transforms, quantized and sparse data --
QUAD = np.array([[0, 0, 0], [0.1, 0, 0], [0.1, 0.1, 0], [0, 0.1, 0]], dtype=np.float32)  # metres
JAW = np.array([[0, -0.01, 0], [0, -0.01, 0], [0, 0, 0], [0, 0, 0]], dtype=np.float32)
BLINK_L_Q = np.array([[0, 0, 0], [0, 0, 0], [0, -3277, 0], [0, 0, 0]], dtype=np.int16)  # normalized
BLINK_R_SPARSE = (3, np.array([0.0, -0.005, 0.0], dtype=np.float32))  # vertex, delta
ROTATION = [0.0, np.sin(np.pi / 4), 0.0, np.cos(np.pi / 4)]  # 90° about +y
SCALE, TRANSLATION = 2.0, [0.0, 1.5, 0.0]


def build_arkit_glb(path: Path) -> None:
    blob = bytearray()

    def view(data: bytes, stride: int | None = None) -> int:
        blob.extend(b"\0" * (-len(blob) % 4))
        views.append(
            pygltflib.BufferView(
                buffer=0, byteOffset=len(blob), byteLength=len(data), byteStride=stride
            )
        )
        blob.extend(data)
        return len(views) - 1

    views: list[pygltflib.BufferView] = []
    acc: list[pygltflib.Accessor] = []

    def accessor(**kw: Any) -> int:
        acc.append(pygltflib.Accessor(**kw))
        return len(acc) - 1

    f32, vec3 = pygltflib.FLOAT, pygltflib.VEC3
    pos = accessor(
        bufferView=view(QUAD.tobytes()),
        componentType=f32,
        count=4,
        type=vec3,
        min=QUAD.min(0).tolist(),
        max=QUAD.max(0).tolist(),
    )
    uv = accessor(
        bufferView=view(QUAD[:, :2].tobytes()), componentType=f32, count=4, type=pygltflib.VEC2
    )
    idx = accessor(
        bufferView=view(np.array([0, 1, 2, 0, 2, 3], np.uint16).tobytes()),
        componentType=pygltflib.UNSIGNED_SHORT,
        count=6,
        type=pygltflib.SCALAR,
    )
    jaw = accessor(
        bufferView=view(JAW.tobytes()),
        componentType=f32,
        count=4,
        type=vec3,
        min=JAW.min(0).tolist(),
        max=JAW.max(0).tolist(),
    )
    padded = np.zeros((4, 4), np.int16)
    padded[:, :3] = BLINK_L_Q
    blink_l = accessor(
        bufferView=view(padded.tobytes(), stride=8),
        componentType=pygltflib.SHORT,
        normalized=True,
        count=4,
        type=vec3,
        min=BLINK_L_Q.min(0).tolist(),
        max=BLINK_L_Q.max(0).tolist(),
    )
    vertex, value = BLINK_R_SPARSE
    sparse = pygltflib.Sparse(
        count=1,
        indices=pygltflib.AccessorSparseIndices(
            bufferView=view(np.array([vertex, 0], np.uint16).tobytes()),
            componentType=pygltflib.UNSIGNED_SHORT,
        ),
        values=pygltflib.AccessorSparseValues(bufferView=view(value.tobytes())),
    )
    blink_r = accessor(
        componentType=f32, count=4, type=vec3, sparse=sparse, min=[0, -0.005, 0], max=[0, 0, 0]
    )
    tri = np.array([[0, 0, 0.05], [0.01, 0, 0.05], [0, 0.01, 0.05]], dtype=np.float32)
    eye = accessor(
        bufferView=view(tri.tobytes()),
        componentType=f32,
        count=3,
        type=vec3,
        min=tri.min(0).tolist(),
        max=tri.max(0).tolist(),
    )
    gltf = pygltflib.GLTF2(
        asset=pygltflib.Asset(version="2.0"),
        extensionsUsed=["KHR_mesh_quantization"],
        extensionsRequired=["KHR_mesh_quantization"],
        scene=0,
        scenes=[pygltflib.Scene(nodes=[0])],
        nodes=[
            pygltflib.Node(children=[1, 2], translation=TRANSLATION),
            pygltflib.Node(mesh=0, rotation=ROTATION, scale=[SCALE] * 3),
            pygltflib.Node(mesh=1),
        ],
        meshes=[
            pygltflib.Mesh(
                name="head",
                primitives=[
                    pygltflib.Primitive(
                        attributes=pygltflib.Attributes(POSITION=pos, TEXCOORD_0=uv),
                        indices=idx,
                        material=0,
                        targets=[pygltflib.Attributes(POSITION=a) for a in (jaw, blink_l, blink_r)],
                    )
                ],
                weights=[0.0, 0.0, 0.0],
                extras={"targetNames": ["jawOpen", "eyeBlinkLeft", "eyeBlinkRight"]},
            ),
            pygltflib.Mesh(
                name="eyes",
                primitives=[
                    pygltflib.Primitive(attributes=pygltflib.Attributes(POSITION=eye), material=1)
                ],
            ),
        ],
        materials=[pygltflib.Material(name="skin"), pygltflib.Material(name="eye")],
        accessors=acc,
        bufferViews=views,
        buffers=[pygltflib.Buffer(byteLength=len(blob))],
    )
    gltf.set_binary_blob(bytes(blob))
    gltf.save_binary(str(path))


def head_to_world_cm(points: np.ndarray, *, translate: bool = True) -> np.ndarray:
    rot = np.array([[0.0, 0, 1], [0, 1, 0], [-1, 0, 0]])  # 90° about +y, by hand
    out = points.astype(np.float64) * SCALE @ rot.T
    return (out + TRANSLATION if translate else out) * 100


def test_arkit_glb_imports_with_its_deltas_and_a_paired_rig(tmp_path: Path) -> None:
    path = tmp_path / "arkit.glb"
    build_arkit_glb(path)
    m = import_glb(path)
    assert m.shape_names == ("jawOpen", "eyeBlinkLeft", "eyeBlinkRight")
    assert m.n_vertices == 7
    np.testing.assert_allclose(m.neutral[:4], head_to_world_cm(QUAD), atol=1e-4)
    np.testing.assert_allclose(
        m.neutral[4:],
        (np.array([[0, 0, 0.05], [0.01, 0, 0.05], [0, 0.01, 0.05]]) + TRANSLATION) * 100,
        atol=1e-4,
    )
    want = np.zeros((3, 7, 3))
    want[0, :4] = head_to_world_cm(JAW, translate=False)
    want[1, :4] = head_to_world_cm(BLINK_L_Q / 32767.0, translate=False)
    blink_r = np.zeros((4, 3))
    blink_r[BLINK_R_SPARSE[0]] = BLINK_R_SPARSE[1]
    want[2, :4] = head_to_world_cm(blink_r, translate=False)
    np.testing.assert_allclose(m.deltas, want, atol=1e-4)
    np.testing.assert_allclose(
        m.evaluate(np.array([[1.0, 0.5, 0.0]]))[0], m.neutral + want[0] + 0.5 * want[1], atol=1e-4
    )
    assert m.rig.name == "generic"
    genes = {g.name: g.shapes for g in m.rig.genes}
    assert genes["eyeBlink"] == ("eyeBlinkLeft", "eyeBlinkRight")
    assert genes["jawOpen"] == ("jawOpen",)
    assert m.rig.expand(np.array([[0.0, 1.0]])).tolist() == [[0.0, 1.0, 1.0]]
    assert [r.name for r in m.regions.values()] == ["skin", "eye"]
    assert m.materials == ("skin", "eye")
    assert m.polygons.tolist() == [[0, 1, 2, -1], [0, 2, 3, -1], [4, 5, 6, -1]]
    np.testing.assert_allclose(m.uvs[:4, 1], 1.0 - QUAD[:, 1])  # glTF's v is flipped back


def test_generic_rig_pairs_twins_and_keeps_asymmetric_shapes_out() -> None:
    names = (
        "jawOpen",
        "jawLeft",
        "jawRight",
        "mouthSmileLeft",
        "mouthSmileRight",
        "browDown_L",
        "browDown_R",
        "eyeLookOutLeft",
        "eyeLookInRight",
        "eyeLookOutRight",
        "eyeLookInLeft",
        "tongueOut",
    )
    rig = generic_rig(names)
    genes = {g.name: g for g in rig.genes}
    assert genes["mouthSmile"].shapes == ("mouthSmileLeft", "mouthSmileRight")
    assert genes["browDown"].shapes == ("browDown_L", "browDown_R")
    assert genes["eyeLookLeft"].shapes == ("eyeLookOutLeft", "eyeLookInRight")  # both eyes one way
    assert genes["eyeLookLeft"].eye and not genes["mouthSmile"].eye
    assert set(rig.excluded) == {"jawLeft", "jawRight"}
    assert "tongueOut" in genes
    assert rig.gaze is None and rig.emotions == {}


# ---- broken files -----------------------------------------------------------------------------
def test_truncated_glb_names_the_file(exported: tuple[Path, ExportReport], tmp_path: Path) -> None:
    path = tmp_path / "cut.glb"
    path.write_bytes(exported[0].read_bytes()[:100_000])
    with pytest.raises(ModelFileError, match=re.escape(str(path)) + ".*truncated"):
        import_glb(path)
    with pytest.raises(ModelFileError, match=re.escape(str(path))):
        emogen.load_model(path)


def test_wrong_magic_names_the_file(exported: tuple[Path, ExportReport], tmp_path: Path) -> None:
    path = tmp_path / "bad.glb"
    path.write_bytes(b"gLTF" + exported[0].read_bytes()[4:])
    with pytest.raises(ModelFileError, match=re.escape(str(path)) + ".*not a GLB"):
        import_glb(path)


def test_bad_json_and_bad_indices_name_the_file(
    exported: tuple[Path, ExportReport], tmp_path: Path
) -> None:
    data = exported[0].read_bytes()
    n_json = struct.unpack_from("<I", data, 12)[0]
    garbled = tmp_path / "garbled.glb"
    garbled.write_bytes(data[:20] + b"{" * n_json + data[20 + n_json :])
    with pytest.raises(ModelFileError, match=re.escape(str(garbled)) + ".*JSON"):
        import_glb(garbled)
    doc, blob = split_glb(data)
    doc["meshes"][0]["primitives"][0]["indices"] = 10_000
    dangling = tmp_path / "dangling.glb"
    dangling.write_bytes(glb_bytes(doc, blob))
    with pytest.raises(ModelFileError, match=re.escape(str(dangling)) + ".*malformed"):
        import_glb(dangling)
    with pytest.raises(ModelFileError, match="missing"):
        import_glb(tmp_path / "nowhere.glb")


# ---- the textured GLB (what the study serves) -------------------------------------------------
TEXTURED_WIRE_LIMIT = 4_000_000  # bytes, gzip -9: mesh, morph targets and both images


@pytest.fixture(scope="module")
def textured(model: FaceModel, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Any]:
    from emogen.appearance.identities import PRESETS
    from emogen.appearance.textures import skin_textures
    from emogen.render.look import default_look, fitted_look

    identity = PRESETS["generic"]
    m = model.with_identity(identity.shape)
    look = default_look()
    textures = skin_textures(m, identity.appearance, irradiance=look.front_irradiance())
    camera = fitted_look(look, m, identity.appearance).camera
    path = tmp_path_factory.mktemp("glb") / "textured.glb"
    report = export_model_glb(m, path, textures=textures, camera=camera)
    return path, (report, textures, camera)


def test_textured_glb_passes_the_khronos_validator(textured: tuple[Path, Any]) -> None:
    path, (report, _, _) = textured
    result = validate(path)
    assert issues(result, 0) == []
    assert issues(result, 1) == []
    assert {"EXT_texture_webp", "KHR_texture_transform"} <= set(result["info"]["extensionsUsed"])
    assert report.gzip_bytes <= TEXTURED_WIRE_LIMIT, str(report)


def test_textured_glb_embeds_the_webp_images_and_camera(
    model: FaceModel, textured: tuple[Path, Any]
) -> None:
    from emogen.render.look import look_json

    path, (_, textures, camera) = textured
    gltf = read_gltf(path)
    doc, blob = gltf.doc, gltf.buffers[0]
    assert "EXT_texture_webp" in doc["extensionsRequired"]
    assert "EXT_texture_webp" in doc["extensionsUsed"]
    assert [i["mimeType"] for i in doc["images"]] == ["image/webp", "image/webp"]

    def image_bytes(k: int) -> bytes:
        view = doc["bufferViews"][doc["images"][k]["bufferView"]]
        return blob[view["byteOffset"] : view["byteOffset"] + view["byteLength"]]

    emogen_extras = doc["asset"]["extras"]["emogen"]
    tex = emogen_extras["textures"]
    skin = doc["textures"][tex["skin"]]["extensions"]["EXT_texture_webp"]["source"]
    detail = doc["textures"][tex["detail"]]["extensions"]["EXT_texture_webp"]["source"]
    assert image_bytes(skin) == textures.albedo_webp
    assert image_bytes(detail) == textures.detail_webp
    samplers = [doc["samplers"][doc["textures"][tex[k]]["sampler"]] for k in ("skin", "detail")]
    assert [s["wrapS"] for s in samplers] == [33071, 10497]  # clamp, repeat
    assert all(s["minFilter"] == 9987 and s["magFilter"] == 9729 for s in samplers)
    # the skin materials (look.json's skin regions) show the atlas, one UDIM tile per 1/2 of u
    skin_part = next(p for p in look_json()["parts"] if p["name"] == "skin")
    assert tuple(skin_part["regions"]) == SKIN_REGIONS
    textured_materials = {
        doc["materials"][p["material"]]["name"]
        for p in doc["meshes"][0]["primitives"]
        if "baseColorTexture" in doc["materials"][p["material"]]["pbrMetallicRoughness"]
    }
    assert textured_materials == {"M_Face", "M_BackHead"}
    face = next(m for m in doc["materials"] if m["name"] == "M_Face")
    base = face["pbrMetallicRoughness"]["baseColorTexture"]
    assert base["index"] == tex["skin"]
    assert base["extensions"]["KHR_texture_transform"]["scale"] == [0.5, 1.0]
    assert emogen_extras["appearance"] == textures.appearance.record()
    cam = emogen_extras["camera"]
    assert cam["position_cm"] == list(camera.position)
    assert cam["fov_y_deg"] == camera.fov_y_deg and cam["near_cm"] == camera.near
    # and it still reads back as the model
    assert import_glb(path).shape_names == model.shape_names
