"""look.json, camera matrices and the per-vertex shading attributes of the real model."""

from __future__ import annotations

import json

import numpy as np
import pytest

from emogen.errors import ConfigError
from emogen.model.geometry import vertex_normals
from emogen.render.look import Camera, default_look, look_from_dict, look_json, parse_colour
from emogen.render.scene import eye_frame, face_mesh, sphere_centre


def test_camera_matrices_follow_opengl_and_three_js() -> None:
    cam = Camera((0.0, 0.0, 10.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 90.0, 1.0, 100.0)
    view = cam.view_matrix()
    assert np.allclose(view @ [0, 0, 0, 1], [0, 0, -10, 1])  # target straight ahead (−z)
    proj = cam.projection_matrix(2.0)
    # three.js PerspectiveCamera(90°, aspect 2, 1, 100): x scale 1/(tan 45°·2), depth terms
    assert np.allclose(proj[[0, 1, 2, 2, 3], [0, 1, 2, 3, 2]], [0.5, 1.0, -101 / 99, -200 / 99, -1])
    # a point on the near plane's top edge lands on the top of the image
    assert np.allclose(cam.project(np.array([[0.0, 1.0, 9.0]]), 100), [[50, 0]])


def test_look_json_is_consistent() -> None:
    look = default_look()
    names = [p.name for p in look.parts]
    assert look.shader["PART_SCLERA"] == names.index("sclera")
    assert look.shader["PART_IRIS"] == names.index("iris")
    defines = look.glsl_defines()
    assert "#define KEY_DIR vec3(-0.250000, 0.350000, 1.000000)" in defines
    assert "#define PART_IRIS 6.000000" in defines
    assert look.footer.startswith("ICT-FaceKit © 2020 USC ICT, MIT licence")
    broken = json.loads(json.dumps(look_json()))
    broken["shader"]["PART_IRIS"] = 2
    with pytest.raises(ConfigError, match="PART_IRIS"):
        look_from_dict(broken)
    del broken["framings"]
    with pytest.raises(ConfigError, match="framings"):
        look_from_dict(broken)
    typo = json.loads(json.dumps(look_json()))
    typo["framing"] = "faces"
    with pytest.raises(ConfigError, match="faces"):
        look_from_dict(typo)
    assert look.with_options(framing="head").camera == look.framings["head"]
    with pytest.raises(ConfigError, match="framing must be one of"):
        look.with_options(framing="torso")
    assert look.shader["PART_SKIN"] == names.index("skin")


@pytest.mark.parametrize(
    ("text", "rgb"),
    [("#ff8000", (1.0, 128 / 255, 0.0)), ("255,255,255", (1, 1, 1)), ("0.5,0.5,0.5", (0.5,) * 3)],
)
def test_parse_colour(text: str, rgb: tuple[float, ...]) -> None:
    assert np.allclose(parse_colour(text), rgb)
    with pytest.raises(ConfigError, match="background must be"):
        parse_colour("blueish")


def test_sphere_centre_recovers_a_sphere() -> None:
    rng = np.random.default_rng(3)
    d = rng.normal(size=(200, 3))
    pts = np.array([1.0, -2.0, 3.0]) + 1.5 * d / np.linalg.norm(d, axis=1, keepdims=True)
    assert np.allclose(sphere_centre(pts), [1, -2, 3], atol=1e-9)


def test_eye_frames_point_forward_through_the_cornea(ict_model) -> None:  # type: ignore[no-untyped-def]
    look = default_look()
    for side, sign in (("left", 1), ("right", -1)):
        shell = ict_model.neutral[ict_model.regions[f"sclera_{side}"].vertices]
        centre, frame = eye_frame(shell, look.eye_axis_vertices)
        assert np.allclose(frame @ frame.T, np.eye(3), atol=1e-9)
        axis = frame[2]
        assert axis[2] > 0.98 and np.sign(axis[0]) == sign  # forward, slightly outward
        # the cornea apex is the shell vertex farthest along the axis
        apex = shell[np.argmax((shell - centre) @ axis)]
        assert (
            np.degrees(np.arccos(np.dot(apex - centre, axis) / np.linalg.norm(apex - centre))) < 2
        )


def test_face_mesh_attributes(ict_model) -> None:  # type: ignore[no-untyped-def]
    look = default_look()
    mesh = face_mesh(ict_model, look)
    names = [p.name for p in look.parts]
    r = ict_model.regions
    assert mesh.part[r["face"].v_start] == names.index("skin")
    assert mesh.part[r["teeth"].v_start] == names.index("teeth")
    assert mesh.part[r["iris_right"].v_start] == names.index("iris")
    # eye directions are unit vectors on the eyes only; side 1 = left
    eye = mesh.eye
    on = eye[:, 3] > 0
    assert np.allclose(np.linalg.norm(eye[on, :3], axis=1), 1, atol=1e-5)
    assert set(np.unique(eye[r["eyeball_left"].vertices, 3])) == {1.0}
    assert not on[r["face"].vertices].any()
    # the cornea part of the shell lies within CORNEA_DEG of the axis (what the shader hides)
    shell = eye[r["sclera_left"].vertices]
    theta = np.degrees(np.arccos(np.clip(shell[:, 2], -1, 1)))
    assert 100 < (theta < look.shader["CORNEA_DEG"]).sum() < 0.5 * len(theta)
    # lash opacity fades with distance from the lid; everything else is opaque
    alpha = mesh.surface[:, 3]
    lashes = alpha[r["eyelashes_left"].vertices]
    assert lashes.max() > 0.8 and lashes.min() == 0.0
    assert np.all(alpha[r["face"].vertices] == 1.0)
    # groups partition the triangles: opaque single-sided first, blended last
    assert sum(g.count for g in mesh.groups) == len(mesh.triangles)
    assert not mesh.groups[0].double_sided and mesh.groups[-1].blended
    hidden = {"lacrimal_left", "eye_blend_left", "eye_occlusion_left"}
    used = np.unique(mesh.triangles)
    for name in hidden:
        assert not np.isin(np.arange(r[name].v_start, r[name].v_stop), used).any()


def test_normals_match_the_reference(ict_model) -> None:  # type: ignore[no-untyped-def]
    mesh = face_mesh(ict_model, default_look())
    v = ict_model.evaluate(np.eye(ict_model.n_shapes)[[0, 26]])
    fast = mesh.normals(v)
    slow = vertex_normals(v, mesh.triangles)
    used = np.unique(mesh.triangles)
    assert np.allclose(fast[:, used], slow[:, used], atol=1e-4)


def test_lid_margin_weights_lie_on_the_lower_lid_and_inner_corner(ict_model) -> None:  # type: ignore[no-untyped-def]
    """The tear-line and caruncle weights (the skin's ``eye`` attribute) against a plain loop:
    only skin vertices within far_cm of a drawn shell vertex carry them, tear weights below the
    eye's centre, caruncle weights on the nose's side of it, and every eye has both."""
    look = default_look()
    mesh = face_mesh(ict_model, look)
    lm = look.lid_margin
    eye = mesh.eye
    skin = mesh.part == look.shader["PART_SKIN"]
    carrying = np.flatnonzero((eye[:, 3] == 0) & (eye[:, :2].max(1) > 0))
    assert np.all(skin[carrying])
    drawn = set(mesh.source.tolist())
    for e in look.eyes:
        shell_ids = [i for i in ict_model.regions[e.shell].vertex_indices() if i in drawn]
        shell = ict_model.neutral[shell_ids].astype(np.float64)
        centre = sphere_centre(shell)
        near = []
        for v in carrying:
            p = ict_model.neutral[v].astype(np.float64)
            if np.linalg.norm(p - centre) < 2.5:
                near.append(v)
                assert min(np.linalg.norm(q - p) for q in shell) < lm["far_cm"]
        near_ids = np.array(near)
        assert len(near_ids) > 20
        offset = ict_model.neutral[near_ids] - centre
        tear, caruncle = eye[near_ids, 0], eye[near_ids, 1]
        assert np.all(offset[tear > 0, 1] < 0.2)  # below the centre (eye frame tilts a little)
        assert np.all(np.sign(offset[caruncle > 0, 0]) == -np.sign(centre[0]))  # nose's side
        assert tear.max() > 0.9 and caruncle.max() > 0.5
