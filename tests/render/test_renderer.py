"""The offscreen renderer on the real ICT-FaceKit model: framing, mouth, eyes, teeth, batches."""

from __future__ import annotations

import numpy as np
import pytest

from emogen.errors import ConfigError, ShapeError
from emogen.render.look import default_look
from emogen.render.renderer import Renderer, render_faces
from emogen.render.scene import eye_frame

BG = np.array([128, 128, 128])


def faces(model, *named: dict[str, float]) -> np.ndarray:  # type: ignore[no-untyped-def]
    return np.stack([model.rig.weights_from_names(d) for d in named])


def pixel(renderer: Renderer, point: np.ndarray) -> tuple[int, int]:
    """(row, column) of a 3-D point (cm) in the renderer's images."""
    x, y = renderer.look.camera.project(np.asarray(point)[None], renderer.size)[0]
    return int(y), int(x)


def region_box(renderer: Renderer, vertices: np.ndarray, margin: int = 0) -> tuple[slice, slice]:
    xy = renderer.look.camera.project(vertices, renderer.size)
    (x0, y0), (x1, y1) = xy.min(0).astype(int) - margin, xy.max(0).astype(int) + margin
    return slice(max(y0, 0), y1), slice(max(x0, 0), x1)


def test_a_face_fills_most_of_the_512_frame(renderer: Renderer, ict_model) -> None:  # type: ignore[no-untyped-def]
    image = renderer.render(faces(ict_model, {}, {"jawOpen": 1.0}))
    assert image.shape == (2, 512, 512, 3) and image.dtype == np.uint8
    for im in image:
        subject = np.any(im != BG, axis=-1)
        rows, cols = np.flatnonzero(subject.any(1)), np.flatnonzero(subject.any(0))
        assert subject.mean() > 0.45  # the head, not a speck in the middle
        assert rows[-1] - rows[0] > 0.9 * 512 and cols[-1] - cols[0] > 0.7 * 512
    # the chin is in the frame, even with the jaw open (the face framing leaves it ~5% room)
    jaw = ict_model.evaluate(faces(ict_model, {"jawOpen": 1.0}))[0][
        ict_model.regions["face"].vertices
    ]
    front = jaw[jaw[:, 2] > 6]
    chin = pixel(renderer, front[np.argmin(front[:, 1])])
    assert 0.6 * 512 < chin[0] < 0.98 * 512


def test_jaw_open_changes_the_mouth_not_the_forehead(renderer: Renderer, ict_model) -> None:  # type: ignore[no-untyped-def]
    neutral, jaw = renderer.render(faces(ict_model, {}, {"jawOpen": 1.0})).astype(int)
    diff = np.abs(neutral - jaw).max(-1)
    v = ict_model.neutral
    face = v[ict_model.regions["face"].vertices]
    mouth = face[
        (np.abs(face[:, 0]) < 3) & (face[:, 1] < -3) & (face[:, 1] > -7) & (face[:, 2] > 8)
    ]
    forehead = face[
        (np.abs(face[:, 0]) < 4) & (face[:, 1] > 7) & (face[:, 1] < 10) & (face[:, 2] > 8)
    ]
    rm, cm = region_box(renderer, mouth)
    rf, cf = region_box(renderer, forehead)
    assert (diff[rm, cm] > 30).mean() > 0.2  # the mouth opened
    assert diff[rf, cf].max() <= 2  # the forehead did not move
    assert rf.stop < rm.start  # forehead above mouth, as a face should be


def test_eyes_have_a_dark_pupil_a_coloured_iris_and_white_sclera(
    renderer: Renderer, ict_model
) -> None:  # type: ignore[no-untyped-def]
    look = default_look()
    image = renderer.render(faces(ict_model, {}, {"PupilDilate": 1.0})).astype(int)
    shell = ict_model.neutral[ict_model.regions["sclera_left"].vertices]
    centre, frame = eye_frame(shell, look.eye_axis_vertices)
    radius = np.linalg.norm(shell - centre, axis=1).min()

    def on_ball(deg: float) -> tuple[int, int]:
        a = np.radians(deg)
        return pixel(renderer, centre + radius * (np.cos(a) * frame[2] + np.sin(a) * frame[0]))

    pupil, iris, sclera = on_ball(0), on_ball(13), on_ball(-40)
    neutral, dilated = image
    assert neutral[pupil].max() < 40  # black pupil
    r, _, b = neutral[iris]
    assert 40 < r < 200 and r > b + 15  # brown iris, not white, not black
    assert neutral[sclera].min() > 170  # white of the eye
    assert dilated[iris].max() < 40  # a dilated pupil: the dark interior shows


def test_grin_shows_teeth(renderer: Renderer, ict_model) -> None:  # type: ignore[no-untyped-def]
    grin = {"jawOpen": 0.3, "mouthSmile": 1.0, "mouthUpperUp": 0.6, "mouthLowerDown": 0.6}
    image = renderer.render(faces(ict_model, grin))[0].astype(int)
    teeth = ict_model.evaluate(faces(ict_model, grin))[0][ict_model.regions["teeth"].vertices]
    rows, cols = region_box(renderer, teeth[teeth[:, 2] > 9.5])
    patch = image[rows, cols]
    whitish = (patch.min(-1) > 170) & (np.ptp(patch, axis=-1) < 60)
    assert whitish.sum() > 150  # a row of teeth, not a dark hole


def test_batch_equals_one_by_one(small_renderer: Renderer, ict_model) -> None:  # type: ignore[no-untyped-def]
    w = faces(ict_model, {}, {"mouthSmile": 0.8}, {"eyeBlink": 1.0, "eyeLookLeft": 1.0})
    batch = small_renderer.render(w)
    for i in range(len(w)):
        assert np.array_equal(batch[i], small_renderer.render(w[i : i + 1])[0])


def test_gaze_turns_the_iris(small_renderer: Renderer, ict_model) -> None:  # type: ignore[no-untyped-def]
    ahead, left = small_renderer.render(faces(ict_model, {}, {"eyeLookLeft": 1.0})).astype(int)
    off = small_renderer.render(faces(ict_model, {"eyeLookLeft": 1.0}), gaze=False)[0]
    assert np.abs(ahead - left).max() > 60
    assert np.abs(off.astype(int) - left).max() > 60  # without gaze only the lids move


def test_identities_render_differently(ict_model) -> None:  # type: ignore[no-untyped-def]
    w = np.zeros((1, ict_model.n_shapes))
    male = render_faces(ict_model.with_identity("male"), w, size=96)[0]
    female = render_faces(ict_model.with_identity("female"), w, size=96)[0]
    width = [np.ptp(np.flatnonzero(np.any(im != BG, -1).any(0))) for im in (male, female)]
    assert width[0] > width[1]  # the male preset is the larger head


def test_background_fov_and_size_options(ict_model) -> None:  # type: ignore[no-untyped-def]
    w = np.zeros((1, ict_model.n_shapes))
    with Renderer(ict_model, size=64, background=(1.0, 1.0, 1.0), supersample=1) as r:
        white = r.render(w)[0]
    assert white.shape == (64, 64, 3) and tuple(white[0, 0]) == (255, 255, 255)
    with Renderer(ict_model, size=64, fov_y_deg=40.0) as r:
        wide = r.render(w)[0]
    narrow = render_faces(ict_model, w, size=64)[0]
    assert np.any(wide != BG, -1).mean() < np.any(narrow != BG, -1).mean()


def test_bad_arguments_name_the_problem(small_renderer: Renderer, ict_model) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ShapeError, match="vertices must have shape"):
        small_renderer.render_vertices(np.zeros((2, 10, 3)))
    with pytest.raises(ShapeError, match="albedo"):
        small_renderer.render_vertices(ict_model.neutral[None], albedo=np.zeros((3, 3)))
    with pytest.raises(ShapeError, match="weights must have shape"):
        small_renderer.render(np.zeros((1, 3)))
    with pytest.raises(ConfigError, match="size must be in"):
        Renderer(ict_model, size=8)
    with pytest.raises(ConfigError, match="field of view"):
        Renderer(ict_model, fov_y_deg=500)


def test_correctives_leave_an_untouched_face_alone(small_renderer: Renderer, ict_model) -> None:  # type: ignore[no-untyped-def]
    w = faces(ict_model, {}, {"browInnerUp": 1.0})
    assert np.array_equal(small_renderer.render(w, correct=True), small_renderer.render(w))
