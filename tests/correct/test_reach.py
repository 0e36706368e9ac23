"""The reach shapes (emogen.correct.reach, rig 2): zero when a driver is zero, activated by the
product of their drivers, left/right mirror images, and no interpenetration added."""

from __future__ import annotations

from importlib import resources

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import cKDTree

from emogen.correct import correct_faces, corrected_vertices
from emogen.correct.measure import CROSSING, Interpenetration, Plausibility
from emogen.errors import ConfigError
from emogen.model.rig_spec import read_rig_spec


@pytest.fixture(scope="module")
def rig1_model(ict_dir):  # type: ignore[no-untyped-def]
    import emogen

    with resources.as_file(resources.files("emogen.data").joinpath("ict_rig_1.toml")) as p:
        return emogen.load_model(ict_dir, rig=p)


def _reach(correctives) -> list[int]:  # type: ignore[no-untyped-def]
    return [i for i, n in enumerate(correctives.combinational_names) if n.startswith("reach_")]


def test_rig_2_declares_the_reach_shapes_and_rig_1_none(
    ict_model, ict_correctives, rig1_model
) -> None:
    names = [ict_correctives.combinational_names[i] for i in _reach(ict_correctives)]
    assert len(names) == 12
    assert {n[:-2] for n in names} == {
        "reach_browDown",
        "reach_browRaiseKnit",
        "reach_duchenne",
        "reach_nasolabial",
        "reach_lidTighten",
        "reach_lipStretch",
    }
    from emogen.correct.faces import model_correctives

    assert not _reach(model_correctives(rig1_model))
    assert rig1_model.model_hash != ict_model.model_hash


def _plain_products(weights: np.ndarray, names: tuple[str, ...], drivers: list[tuple]) -> list:
    """Each reach shape's activation by a plain loop over its driver names."""
    out = []
    for face in weights:
        row = []
        for d in drivers:
            p = 1.0
            for name in d:
                p *= float(face[names.index(name)])
            row.append(p)
        out.append(row)
    return out


@settings(max_examples=25, deadline=None)
@given(data=st.data())
def test_activation_is_the_product_and_zero_when_a_driver_is_zero(
    ict_model, ict_correctives, data
) -> None:
    c = ict_correctives
    idx = _reach(c)
    n = ict_model.n_shapes
    w = np.array(
        data.draw(st.lists(st.floats(0, 1), min_size=n, max_size=n), label="weights"), dtype=float
    )[None]
    k = data.draw(st.sampled_from(idx), label="reach shape")
    off = data.draw(st.sampled_from(c.driver_names(k)), label="driver set to 0")
    w[0, ict_model.shape_index("mouthClose")] = 0.0  # no companion cap in the reference
    zero = w.copy()
    zero[0, ict_model.shape_index(off)] = 0.0
    r = correct_faces(ict_model, np.vstack([w, zero]))
    drivers = [c.driver_names(i) for i in idx]
    expected = _plain_products(r.weights, ict_model.shape_names, drivers)
    np.testing.assert_allclose(r.combinational[:, idx], expected, rtol=1e-12, atol=0)
    assert r.combinational[1, k] == 0.0


@settings(max_examples=10, deadline=None)
@given(data=st.data())
def test_a_face_without_any_reach_driver_is_rig_1_face(
    ict_model, ict_correctives, rig1_model, data
) -> None:
    c = ict_correctives
    used = {d for i in _reach(c) for d in c.driver_names(i)}
    free = [s for s in ict_model.shape_names if s not in used and s != "mouthClose"]
    picked = data.draw(st.lists(st.sampled_from(free), min_size=1, max_size=6, unique=True))
    values = data.draw(st.lists(st.floats(0, 1), min_size=len(picked), max_size=len(picked)))
    w = ict_model.rig.weights_from_names(dict(zip(picked, values, strict=True)))[None]
    new = corrected_vertices(ict_model, correct_faces(ict_model, w), gaze=False)
    old = corrected_vertices(rig1_model, correct_faces(rig1_model, w), gaze=False)
    np.testing.assert_allclose(new, old, atol=1e-5)


def test_left_and_right_reach_shapes_mirror_each_other(ict_model, ict_correctives) -> None:
    """Against the mesh's own mirror map (nearest vertex of each reflected vertex, scipy)."""
    neutral = ict_model.base_neutral.astype(np.float64)
    dist, mirror = cKDTree(neutral).query(neutral * [-1.0, 1.0, 1.0])
    exact = dist < 1e-4
    assert exact.mean() > 0.98
    c = ict_correctives
    for i in _reach(c):
        name = c.combinational_names[i]
        if not name.endswith("_L"):
            continue
        j = c.combinational_names.index(name[:-2] + "_R")
        left, right = c.combinational_deltas[i], c.combinational_deltas[j]
        assert np.abs(left).max() > 0.1, name
        # within 10 µm (coincident and midline vertices)
        reflected = left[mirror] * [-1.0, 1.0, 1.0]
        np.testing.assert_allclose(right[exact], reflected[exact], atol=1e-3, err_msg=name)


def test_no_interpenetration_or_lid_crossing_added_on_ga_faces(
    ict_model, rig1_model, ga_weights, mouth
) -> None:
    """≥ 500 GA faces, corrected with rig 1 and rig 2, measured by the independent tests."""
    w, _ = ga_weights
    neutral = ict_model.base_neutral.astype(np.float64)
    inside = Interpenetration.build(neutral, ict_model.regions, mouth)
    plaus = Plausibility.build(
        neutral, ict_model.polygons, ict_model.regions, mouth, ict_model.deltas
    )
    counts = {}
    for label, model in (("rig1", rig1_model), ("rig2", ict_model)):
        v = corrected_vertices(model, correct_faces(model, w), gaze=False)
        m = plaus.measure(v)
        counts[label] = (
            int(inside.penetrating(v).sum()),
            int((m["lid_crossing"] > CROSSING).sum()),
            int((m["lip_overlap"] > CROSSING).sum()),
        )
    assert counts["rig2"][0] <= max(counts["rig1"][0], 0.005 * len(w)), counts
    assert counts["rig2"][1] <= counts["rig1"][1], counts
    assert counts["rig2"][2] <= counts["rig1"][2] + 1, counts


def test_the_anger_prototype_reaches_further_with_rig_2(ict_model, rig1_model) -> None:
    """AU4's inner brow: lowered and drawn together about twice as far as rig 1's."""
    lm = ict_model.landmarks
    out = {}
    for label, model in (("rig1", rig1_model), ("rig2", ict_model)):
        w = model.rig.weights_from_names({"browDown": 1.0})[None]
        v = corrected_vertices(model, correct_faces(model, w), gaze=False)[0]
        n = model.base_neutral
        lowered = -(v[lm[[21, 22]], 1] - n[lm[[21, 22]], 1]).mean()
        gap = (v[lm[22], 0] - v[lm[21], 0]) - (n[lm[22], 0] - n[lm[21], 0])
        out[label] = (lowered, -gap)
    assert out["rig2"][0] >= 1.7 * out["rig1"][0] and out["rig2"][1] >= 1.5 * out["rig1"][1]


def test_a_reach_version_that_does_not_exist_is_named(tmp_path) -> None:
    rig = tmp_path / "rig.toml"
    rig.write_text('name = "x"\n[reach]\nversion = 2\n')
    with pytest.raises(ConfigError, match=r"reach\.version.*got 2"):
        read_rig_spec(rig)
