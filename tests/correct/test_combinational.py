"""Combinational correctives: the double-counting rule, activations, companions, rig entries."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from emogen.correct import correct_faces, evaluate_corrected, model_correctives
from emogen.correct.combinational import activations, double_counted, mirror, overlap_score
from emogen.errors import ConfigError

vec = arrays(np.float64, (5, 3), elements=st.floats(-1, 1))


def test_parallel_offsets_count_the_smaller_twice() -> None:
    u = np.array([[0.0, 2.0, 0.0], [0.0, 0.0, 0.0]])
    w = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
    o = double_counted(u, w)
    np.testing.assert_allclose(o[0], [0, 0.9, 0])  # close to min(2, 1) along the pair
    np.testing.assert_allclose(o[1], 0)  # only one shape moves this vertex
    same = double_counted(u, u)
    np.testing.assert_allclose(same, u)  # a shape with itself: all of it is counted twice
    assert overlap_score(u, u) == pytest.approx(1.0)


@settings(max_examples=60, deadline=None)
@given(u=vec, w=vec)
def test_double_counting_is_symmetric_bounded_and_zero_for_opposite_pushes(u, w) -> None:
    o = double_counted(u, w)
    np.testing.assert_allclose(o, double_counted(w, u), atol=1e-12)
    small = np.minimum(np.linalg.norm(u, axis=1), np.linalg.norm(w, axis=1))
    assert np.all(np.linalg.norm(o, axis=1) <= small + 1e-12)
    np.testing.assert_allclose(double_counted(u, -u), 0, atol=1e-12)


def test_activation_is_the_product_of_the_drivers() -> None:
    w = np.array([[0.5, 0.4, 1.0], [0.0, 1.0, 1.0]])
    drivers = np.array([[0, 1], [1, 2], [2, 0]])
    mask = np.array([[True, True], [True, True], [True, False]])
    np.testing.assert_allclose(activations(w, drivers, mask), [[0.2, 0.4, 1.0], [0.0, 1.0, 1.0]])


def test_mirror() -> None:
    assert mirror("eyeBlink_L") == "eyeBlink_R" and mirror("jawOpen") == "jawOpen"


def test_ict_derived_set_is_symmetric_documented_and_deterministic(
    ict_model, ict_correctives
) -> None:
    from emogen.correct.correctives import build_correctives

    c = ict_correctives
    derived = [i for i in range(c.n_combinational) if not np.isnan(c.scores[i])]  # not reach
    pairs = {c.driver_names(i) for i in derived}
    assert len(pairs) >= 20
    for a, b in pairs:
        assert (mirror(a), mirror(b)) in pairs or (mirror(b), mirror(a)) in pairs
        assert not {a, b} & set(ict_model.rig.excluded)
        assert "jawOpen" not in (a, b)
    assert ("eyeBlink_L", "eyeLookDown_L") in pairs and ("mouthDimple_L", "mouthSmile_L") in pairs
    again = build_correctives(ict_model)
    assert again.combinational_names == c.combinational_names
    np.testing.assert_array_equal(again.combinational_deltas, c.combinational_deltas)
    np.testing.assert_array_equal(again.collision_deltas, c.collision_deltas)


def test_a_pair_at_full_weight_moves_no_further_than_its_larger_shape(
    ict_model, ict_correctives
) -> None:
    c = ict_correctives
    i = c.combinational_names.index("corr_eyeBlink_L_eyeLookDown_L")
    a, b = (ict_model.shape_index(s) for s in c.driver_names(i))
    u, w = ict_model.deltas[a], ict_model.deltas[b]
    combined = u + w + c.combinational_deltas[i]
    big = np.maximum(np.linalg.norm(u, axis=1), np.linalg.norm(w, axis=1))
    naive = np.linalg.norm(u + w, axis=1)
    fixed = np.linalg.norm(combined, axis=1)
    moved = big > 0.05
    assert np.all(fixed[moved] <= naive[moved] + 1e-5)
    # what stays beyond the larger shape is the part of the offsets that is not shared
    assert np.median(fixed[moved] / big[moved]) < 1.1 < np.median(naive[moved] / big[moved])


def test_mouth_close_is_capped_at_jaw_open(ict_model) -> None:
    w = ict_model.rig.weights_from_names({"mouthClose": 0.8, "jawOpen": 0.3})[None]
    r = correct_faces(ict_model, w)
    assert r.core[0, ict_model.shape_index("mouthClose")] == 0.8
    assert r.weights[0, ict_model.shape_index("mouthClose")] == pytest.approx(0.3)
    alone = correct_faces(ict_model, ict_model.rig.weights_from_names({"mouthClose": 1.0})[None])
    assert alone.weights[0, ict_model.shape_index("mouthClose")] == 0.0


RIG_WITH_FILE = """
name = "tiny"
[[correctives]]
name = "fix_smile"
drivers = ["smile_L", "smile_R"]
file = "fix_smile.obj"
[[correctives]]
name = "fix_jaw_smile"
drivers = ["jawOpen", "smile_L"]
[companions]
smile_R = "smile_L"
"""


def test_artist_corrective_from_an_obj_file(tiny_dir: Path) -> None:
    import emogen
    from emogen.model.io.obj import parse_vertices

    neutral = parse_vertices(tiny_dir / "generic_neutral_mesh.obj")
    shape = neutral + np.arange(15).reshape(5, 3) * 0.01
    lines = [f"v {x} {y} {z}" for x, y, z in shape] + ["f 1 2 3"]
    (tiny_dir.parent / "fix_smile.obj").write_text("\n".join(lines) + "\n")
    (tiny_dir.parent / "rig.toml").write_text(RIG_WITH_FILE)
    model = emogen.load_model(tiny_dir, rig=tiny_dir.parent / "rig.toml")
    c = model_correctives(model)
    assert c.combinational_names == ("fix_smile", "fix_jaw_smile")
    assert c.n_collision == 0  # no mouth regions on this model
    np.testing.assert_allclose(c.combinational_deltas[0], shape - neutral, atol=1e-6)
    w = np.array([[0.5, 0.4, 0.9, 0, 0, 0, 0]])  # jawOpen, smile_L, smile_R (capped at 0.4)
    w = w[:, : model.n_shapes]
    r = correct_faces(model, w)
    np.testing.assert_allclose(r.combinational, [[0.4 * 0.4, 0.5 * 0.4]])
    verts = evaluate_corrected(model, w)
    plain = model.evaluate(r.weights)
    expect = plain[0] + 0.16 * c.combinational_deltas[0] + 0.2 * c.combinational_deltas[1]
    np.testing.assert_allclose(verts[0], expect, atol=1e-5)


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ('[[correctives]]\nname = "x"\ndrivers = ["nope", "smile_L"]\n', "nope"),
        (
            '[[correctives]]\nname = "jawOpen"\ndrivers = ["smile_L", "smile_R"]\n',
            "already a shape",
        ),
        ('[[correctives]]\nname = "x"\ndrivers = ["smile_L"]\n', "exactly 2 drivers"),
        ('[companions]\nsmile_L = "nothing"\n', "nothing"),
        ("[derive_correctives]\nmin_overlap = 0\n", "min_overlap"),
    ],
)
def test_rig_corrective_errors_name_the_problem(tiny_dir: Path, text: str, match: str) -> None:
    import emogen

    (tiny_dir.parent / "bad.toml").write_text('name = "tiny"\n' + text)
    with pytest.raises(ConfigError, match=match):
        emogen.load_model(tiny_dir, rig=tiny_dir.parent / "bad.toml")
