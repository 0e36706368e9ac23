"""The reach shapes (emogen.correct.reach, rigs 2 and 3): zero when a driver is zero, activated
by the product of their drivers, left/right mirror images, no interpenetration added, and what
rig 3's prototypes reach (lips parted in the smile and in fear, anger's thinned lips)."""

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


@pytest.fixture(scope="module")
def rig2_model(ict_dir):  # type: ignore[no-untyped-def]
    import emogen

    with resources.as_file(resources.files("emogen.data").joinpath("ict_rig_2.toml")) as p:
        return emogen.load_model(ict_dir, rig=p)


VERSION_1 = {
    "reach_browDown",
    "reach_browRaiseKnit",
    "reach_duchenne",
    "reach_nasolabial",
    "reach_lidTighten",
    "reach_lipStretch",
}


def test_rig_3_declares_version_2_rig_2_version_1_and_rig_1_none(
    ict_model, ict_correctives, rig2_model, rig1_model
) -> None:
    from emogen.correct.faces import model_correctives

    names = [ict_correctives.combinational_names[i] for i in _reach(ict_correctives)]
    assert len(names) == 20
    assert {n[:-2] for n in names} == VERSION_1 | {
        "reach_smileOpen",
        "reach_lipTightener",
        "reach_tightenRolledUpper",
        "reach_tightenRolledLower",
    }
    old = model_correctives(rig2_model)
    assert {old.combinational_names[i][:-2] for i in _reach(old)} == VERSION_1
    assert len(_reach(old)) == 12
    assert not _reach(model_correctives(rig1_model))
    hashes = {m.model_hash for m in (ict_model, rig2_model, rig1_model)}
    assert len(hashes) == 3


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
    """≥ 500 GA faces, corrected with rig 1 and rig 3, measured by the independent tests (over
    3,000 GA faces, seed 11, both rigs have none: docs/model.md, "Budgets")."""
    w, _ = ga_weights
    neutral = ict_model.base_neutral.astype(np.float64)
    inside = Interpenetration.build(neutral, ict_model.regions, mouth)
    plaus = Plausibility.build(
        neutral, ict_model.polygons, ict_model.regions, mouth, ict_model.deltas
    )
    counts = {}
    for label, model in (("rig1", rig1_model), ("rig3", ict_model)):
        v = corrected_vertices(model, correct_faces(model, w), gaze=False)
        m = plaus.measure(v)
        counts[label] = (
            int(inside.penetrating(v).sum()),
            int((m["lid_crossing"] > CROSSING).sum()),
            int((m["lip_overlap"] > CROSSING).sum()),
        )
    assert counts["rig3"][0] <= counts["rig1"][0], counts
    assert counts["rig3"][1] <= counts["rig1"][1], counts
    assert counts["rig3"][2] <= counts["rig1"][2] + 1, counts


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
    rig.write_text('name = "x"\n[reach]\nversion = 3\n')
    with pytest.raises(ConfigError, match=r"reach\.version.*got 3"):
        read_rig_spec(rig)


def _mouth(model, emotions: list[str]) -> dict[str, tuple[float, float, float, float]]:  # type: ignore[no-untyped-def]
    """Per prototype (core genes at 1, corrected), in mm from the Multi-PIE landmarks: the
    inner lips' separation (62–66), the upper and lower red lip heights (51–62, 66–57) and the
    mouth's width (48–54)."""
    lm = model.landmarks
    w = np.array(
        [
            model.rig.weights_from_names(dict.fromkeys(model.rig.emotions[e].core, 1.0))
            for e in emotions
        ]
    )
    v = corrected_vertices(model, correct_faces(model, w), gaze=False) * 10
    out = {}
    for e, f in zip(emotions, v, strict=True):
        out[e] = (
            f[lm[62], 1] - f[lm[66], 1],
            f[lm[51], 1] - f[lm[62], 1],
            f[lm[66], 1] - f[lm[57], 1],
            f[lm[54], 0] - f[lm[48], 0],
        )
    return out


def test_rig_3_prototypes_part_the_lips_and_thin_anger_s(ict_model, rig2_model) -> None:
    """Happy (6+12+25) and fear (…+20+25) part the lips; surprise's jaw drop stays far wider
    than fear's; anger's red lips thinned (AU23) to ≤ 0.6 × rig 2's; rig 2's prototypes as
    before (lips closed)."""
    emotions = ["happy", "fearful", "surprised", "angry"]
    new, old = _mouth(ict_model, emotions), _mouth(rig2_model, emotions)
    for e in ("happy", "fearful"):
        assert old[e][0] < 2.0 and new[e][0] >= 5.0, (e, old[e], new[e])
    assert new["surprised"][0] >= 3 * new["fearful"][0]
    assert new["fearful"][3] >= new["surprised"][3] + 15  # stretched sideways, not dropped
    for k in (1, 2):
        assert new["angry"][k] <= 0.6 * old["angry"][k], (new["angry"], old["angry"])
    assert abs(new["angry"][0]) < 1.0  # pressed, not parted


def test_a_rolled_lip_pressed_is_rolled_no_further_than_ict_s_full_roll(
    ict_model, rig2_model
) -> None:
    """mouthPress with mouthRollLower at 1: rig 3's lower lip is where rig 2's is (the roll
    capped at 1), while the pressed, unrolled upper lip is thinned (the tightener)."""
    lm = ict_model.landmarks
    w = ict_model.rig.weights_from_names({"mouthPress": 1.0, "mouthRollLower": 1.0})[None]
    new, old = (
        corrected_vertices(m, correct_faces(m, w), gaze=False)[0] for m in (ict_model, rig2_model)
    )
    lower = lm[[57, 66]]
    np.testing.assert_allclose(new[lower], old[lower], atol=0.02)  # 0.2 mm
    red_upper = lambda v: v[lm[51], 1] - v[lm[62], 1]  # noqa: E731
    assert red_upper(new) <= red_upper(old) - 0.2
