"""FaceModel.evaluate against plain references, batching properties, gaze and identities."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from emogen.errors import ConfigError, ShapeError

weights_st = st.integers(1, 6).flatmap(
    lambda n: arrays(np.float32, (n, 7), elements=st.floats(0, 1, width=32))
)


def plain_blend(model, w: np.ndarray) -> np.ndarray:
    """Reference: for each face, v = B0 + Σ_k w_k Δ_k, one shape at a time."""
    out = np.empty((len(w), model.n_vertices, 3))
    for i, row in enumerate(w):
        v = model.neutral.astype(np.float64).copy()
        for k in range(model.n_shapes):
            v += float(row[k]) * model.deltas[k]
        out[i] = v
    return out


@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(w=weights_st, chunk=st.integers(1, 4))
def test_tiny_evaluate_matches_plain_loop(tiny_model, w, chunk) -> None:
    got = tiny_model.evaluate(w, chunk=chunk)
    np.testing.assert_allclose(got, plain_blend(tiny_model, w), atol=1e-5)
    for i in range(len(w)):
        np.testing.assert_allclose(got[i], tiny_model.evaluate(w[i : i + 1])[0], atol=1e-6, rtol=0)


def test_zero_weights_give_neutral(ict_model) -> None:
    out = ict_model.evaluate(np.zeros((3, ict_model.n_shapes)))
    np.testing.assert_array_equal(out, np.broadcast_to(ict_model.neutral, out.shape))


def test_real_model_random_batch_matches_plain_loop(ict_model) -> None:
    rng = np.random.default_rng(3)
    w = rng.random((4, ict_model.n_shapes)).astype(np.float32)
    got = ict_model.evaluate(w, gaze=False, chunk=3)
    np.testing.assert_allclose(got, plain_blend(ict_model, w), atol=2e-4)


def test_chunks_stream_the_same_faces(ict_model) -> None:
    rng = np.random.default_rng(4)
    w = rng.random((7, ict_model.n_shapes)).astype(np.float32)
    full = ict_model.evaluate(w)
    seen = 0
    for sl, verts in ict_model.evaluate_chunks(w, chunk=3):
        np.testing.assert_allclose(verts, full[sl], atol=1e-5, rtol=0)
        seen += verts.shape[0]
    assert seen == 7


def test_bad_weight_shapes_are_named(ict_model) -> None:
    with pytest.raises(ShapeError, match=r"\(n_faces, 57\); got \(2, 56\)"):
        ict_model.evaluate(np.zeros((2, 56)))
    with pytest.raises(ShapeError, match="1-D"):
        ict_model.evaluate(np.zeros(57))
    with pytest.raises(ShapeError, match="NaN"):
        ict_model.evaluate(np.full((1, 57), np.nan))
    with pytest.raises(ShapeError, match="unknown shape 'jawOpn'"):
        ict_model.shape_index("jawOpn")


def test_model_arrays_are_read_only(ict_model) -> None:
    with pytest.raises(ValueError):
        ict_model.deltas[0, 0, 0] = 1.0
    with pytest.raises(ValueError):
        ict_model.neutral[0, 0] = 1.0


# ---- gaze -----------------------------------------------------------------------------


def _iris_centre(verts: np.ndarray, model, side: str) -> np.ndarray:
    """The front of the inner eyeball (the 'iris' region is a whole ball): its 20 most +z points."""
    sl = model.regions[f"iris_{side}"].vertices
    front = np.argsort(model.neutral[sl, 2])[-20:]
    return verts[sl][front].mean(0)


def test_gaze_turns_both_eyeballs_rigidly_the_same_way(ict_model) -> None:
    w = ict_model.rig.weights_from_names({"eyeLookLeft": 1.0})
    moved = ict_model.evaluate(w[None])[0]
    still = ict_model.evaluate(w[None], gaze=False)[0]
    for side in ("left", "right"):
        # toward the subject's left is +x; both irises move that way (conjugate gaze)
        shift = _iris_centre(moved, ict_model, side) - _iris_centre(still, ict_model, side)
        assert shift[0] > 0.3 and abs(shift[1]) < 0.05, (side, shift)
        sl = ict_model.regions[f"eyeball_{side}"].vertices
        a, b = moved[sl], still[sl]
        # rigid: pairwise distances of a vertex sample are preserved
        idx = np.arange(0, a.shape[0], 37)
        da = np.linalg.norm(a[idx, None] - a[None, idx], axis=-1)
        db = np.linalg.norm(b[idx, None] - b[None, idx], axis=-1)
        np.testing.assert_allclose(da, db, atol=1e-4)
    # the rest of the face is untouched by the eyeball rotation
    face = ict_model.regions["face"].vertices
    np.testing.assert_array_equal(moved[face], still[face])


def test_gaze_follows_the_lids(ict_model) -> None:
    """Independent reference: the direction ICT's own eyeLook shapes move the upper lid."""
    for gene, axis in (
        ("eyeLookUp", 1),
        ("eyeLookDown", 1),
        ("eyeLookLeft", 0),
        ("eyeLookRight", 0),
    ):
        w = ict_model.rig.weights_from_names({gene: 1.0})
        delta = (w @ ict_model.deltas.reshape(ict_model.n_shapes, -1)).reshape(-1, 3)
        lid = ict_model.regions["face"].vertices
        lid_motion = delta[lid][np.linalg.norm(delta[lid], axis=1) > 0.05].mean(0)
        moved = ict_model.evaluate(w[None])[0]
        still = ict_model.evaluate(w[None], gaze=False)[0]
        iris = _iris_centre(moved, ict_model, "left") - _iris_centre(still, ict_model, "left")
        assert np.sign(iris[axis]) == np.sign(lid_motion[axis]), gene


# ---- identities -----------------------------------------------------------------------


def _landmarks(ict_dir) -> np.ndarray:
    return np.array(
        json.loads((ict_dir / "vertex_indices.json").read_text())["idx_to_landmark_verts"]
    )


def test_male_and_female_presets_differ_as_documented(ict_model, ict_dir) -> None:
    lm = _landmarks(ict_dir)
    male = ict_model.with_identity("male")
    female = ict_model.with_identity("female")
    assert male.identity_label == "male" and female.identity_label == "female"

    def jaw_width(m) -> float:
        p = m.neutral[lm]
        return float(np.linalg.norm(p[4] - p[12]))

    def nose_length(m) -> float:
        p = m.neutral[lm]
        return float(np.linalg.norm(p[27] - p[33]))

    assert jaw_width(male) > jaw_width(ict_model) > jaw_width(female)
    assert nose_length(male) > nose_length(female)
    # expression deltas are shared, not copied
    assert male.deltas is ict_model.deltas


def test_identity_errors_and_sampling(ict_model) -> None:
    with pytest.raises(ConfigError, match="unknown identity 'mal'"):
        ict_model.with_identity("mal")
    with pytest.raises(ConfigError, match="21 coefficients; this model has 20"):
        ict_model.with_identity(np.zeros(21))
    a = ict_model.sample_identity(rng=np.random.default_rng(5))
    b = ict_model.sample_identity(rng=np.random.default_rng(5))
    np.testing.assert_array_equal(a, b)
    short = ict_model.with_identity([0.5])  # fewer coefficients: the rest are zero
    ref = ict_model.base_neutral + 0.5 * ict_model.identity_deltas[0]
    np.testing.assert_allclose(short.neutral, ref, atol=1e-5)
    assert ict_model.with_identity(None).identity_label == "generic"


def test_mixed_gaze_batch_equals_faces_one_by_one(ict_model) -> None:
    rig = ict_model.rig
    w = np.stack(
        [
            rig.weights_from_names({"eyeLookUp": 0.7, "jawOpen": 0.3}),
            rig.weights_from_names({"jawOpen": 0.3}),
            rig.weights_from_names({"eyeLookRight": 0.4, "eyeLookDown": 0.2}),
        ]
    )
    batch = ict_model.evaluate(w)
    for i in range(len(w)):
        np.testing.assert_allclose(batch[i], ict_model.evaluate(w[i : i + 1])[0], atol=1e-5, rtol=0)
