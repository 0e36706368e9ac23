"""The ICT-FaceKit folder as loaded, checked against the OBJ files read independently."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

import emogen
from emogen.errors import ModelFileError
from emogen.model.regions import ict_regions
from tests.conftest import read_obj_vertices_plainly


def test_counts_and_shape_list(ict_model, ict_dir: Path) -> None:
    expressions = json.loads((ict_dir / "vertex_indices.json").read_text())["expressions"]
    assert ict_model.n_vertices == 26719
    assert len(ict_model.polygons) == 26384
    assert set(ict_model.shape_names) == set(expressions) | {
        "cheekRaiser_L",
        "cheekRaiser_R",
        "PupilDilate_L",
        "PupilDilate_R",
    }
    assert ict_model.n_shapes == 57
    assert ict_model.n_identity_modes == 20


def test_neutral_matches_obj(ict_model, ict_dir: Path) -> None:
    ref = read_obj_vertices_plainly(ict_dir / "generic_neutral_mesh.obj")
    np.testing.assert_allclose(ict_model.neutral, ref, atol=1e-5, rtol=0)


def test_every_one_hot_reproduces_its_obj(ict_model, ict_dir: Path) -> None:
    eye = np.eye(ict_model.n_shapes, dtype=np.float32)
    worst = 0.0
    for k, name in enumerate(ict_model.shape_names):
        got = ict_model.evaluate(eye[k : k + 1], gaze=False)[0]
        ref = read_obj_vertices_plainly(ict_dir / f"{name}.obj")
        err = float(np.abs(got - ref).max())
        worst = max(worst, err)
        assert err <= 1e-4, f"{name}: max abs error {err}"
    assert worst > 0  # float32 storage is not bit-exact: the comparison really ran


def test_identity_modes_reproduce_their_obj(ict_model, ict_dir: Path) -> None:
    for i in (0, 7, 19):
        beta = np.zeros(ict_model.n_identity_modes)
        beta[i] = 1.0
        got = ict_model.with_identity(beta).neutral
        ref = read_obj_vertices_plainly(ict_dir / f"identity{i:03d}.obj")
        assert np.abs(got - ref).max() <= 1e-4


def test_polygons_match_obj_face_lines(ict_model, ict_dir: Path) -> None:
    faces = []
    for line in (ict_dir / "generic_neutral_mesh.obj").read_text().splitlines():
        if line.startswith("f "):
            idx = [int(c.split("/")[0]) - 1 for c in line.split()[1:]]
            faces.append(idx + [-1] * (4 - len(idx)))
    np.testing.assert_array_equal(ict_model.polygons, np.array(faces))
    # Triangulation covers each quad by two triangles with the quad's corners.
    tris = ict_model.faces
    assert len(tris) == 2 * int((ict_model.polygons[:, 3] >= 0).sum()) + int(
        (ict_model.polygons[:, 3] < 0).sum()
    )


def test_regions_follow_readme_ranges(ict_model) -> None:
    regions = ict_regions()
    # Sub-meshes tile the vertex and polygon ranges exactly.
    parts = [r for r in regions.values() if r.group == "part"]
    assert sum(r.n_vertices for r in parts) == 26719
    teeth = [r for r in regions.values() if r.group == "tooth"]
    assert len(teeth) == 32
    assert sum(r.n_vertices for r in teeth) == regions["teeth"].n_vertices
    # Head/neck and the mouth and eye sockets are stitched to the face's border vertices;
    # every other part (and every tooth) is a closed-off mesh using only its own range.
    stitched = {"head_neck", "mouth_socket", "eye_socket_left", "eye_socket_right"}
    face = regions["face"]
    for r in (*parts, *teeth):
        used = ict_model.polygons[r.polygons]
        used = used[used >= 0]
        own = (used >= r.v_start) & (used < r.v_stop)
        if r.name in stitched:
            assert np.all(own | ((used >= face.v_start) & (used < face.v_stop))), r.name
            assert own.mean() > 0.9, r.name
        else:
            assert np.all(own), r.name
    for name in (
        "face",
        "mouth_socket",
        "gums_tongue",
        "sclera_left",
        "iris_right",
        "eyelashes_left",
    ):
        assert name in ict_model.regions


# ---- broken folders -------------------------------------------------------------------


def _copy(src: Path, dst: Path) -> Path:
    shutil.copytree(src, dst)
    return dst


def test_missing_folder_names_it(tmp_path: Path) -> None:
    with pytest.raises(emogen.ModelNotFoundError, match="nothere"):
        emogen.load_model(tmp_path / "nothere")


def test_missing_shape_names_file(tiny_dir: Path) -> None:
    (tiny_dir / "smile_R.obj").unlink()
    with pytest.raises(ModelFileError, match=r"smile_R\.obj"):
        emogen.load_model(tiny_dir, rig=tiny_dir.parent / "tiny_rig.toml")


def test_extra_shape_is_rejected(tiny_dir: Path) -> None:
    shutil.copy(tiny_dir / "jawOpen.obj", tiny_dir / "jawOpen_copy.obj")
    with pytest.raises(ModelFileError, match=r"jawOpen_copy\.obj"):
        emogen.load_model(tiny_dir, rig=tiny_dir.parent / "tiny_rig.toml")


def test_vertex_count_mismatch_names_file_and_counts(tiny_dir: Path) -> None:
    path = tiny_dir / "jawOpen.obj"
    lines = path.read_text().splitlines()
    first_v = next(i for i, line in enumerate(lines) if line.startswith("v "))
    del lines[first_v]
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(
        ModelFileError, match=r"'jawOpen' has 4 vertices, neutral has 5 .*jawOpen\.obj"
    ):
        emogen.load_model(tiny_dir, rig=tiny_dir.parent / "tiny_rig.toml")


def test_malformed_line_names_file_and_line(tiny_dir: Path) -> None:
    path = tiny_dir / "smile_L.obj"
    lines = path.read_text().splitlines()
    lines[5] = "v 0.1 oops 0.3"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(ModelFileError, match=r"smile_L\.obj:6: malformed line 'v 0\.1 oops 0\.3'"):
        emogen.load_model(tiny_dir, rig=tiny_dir.parent / "tiny_rig.toml")


def test_bad_face_index_names_line(tiny_dir: Path) -> None:
    path = tiny_dir / "generic_neutral_mesh.obj"
    path.write_text(path.read_text().replace("f 1/1 3/3 5/5", "f 1/1 3/3 9/5"))
    with pytest.raises(
        ModelFileError, match=r"generic_neutral_mesh\.obj:\d+: face refers to vertex 9"
    ):
        emogen.load_model(tiny_dir, rig=tiny_dir.parent / "tiny_rig.toml")


def test_corrupt_index_json(tiny_dir: Path) -> None:
    (tiny_dir / "vertex_indices.json").write_text("{not json")
    with pytest.raises(ModelFileError, match=r"vertex_indices\.json: not valid JSON"):
        emogen.load_model(tiny_dir, rig=tiny_dir.parent / "tiny_rig.toml")


def test_tiny_model_loads_against_plain_reference(tiny_dir: Path, tiny_model) -> None:
    ref = read_obj_vertices_plainly(tiny_dir / "smile_L.obj")
    w = np.zeros((1, tiny_model.n_shapes))
    w[0, tiny_model.shape_index("smile_L")] = 1
    np.testing.assert_allclose(tiny_model.evaluate(w)[0], ref, atol=1e-5)
