"""correct_faces / evaluate_corrected: exactness, records, and the before/after figures."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from emogen.correct import correct_faces, corrected_vertices, evaluate_corrected
from emogen.correct.measure import Interpenetration
from emogen.errors import ShapeError

# genes that never touch the mouth: a face made of them cannot collide
AWAY_FROM_MOUTH = (
    "browDown",
    "browInnerUp",
    "browOuterUp",
    "eyeWide",
    "eyeLookLeft",
    "eyeLookUp",
    "PupilDilate",
)


@settings(
    max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    values=st.lists(st.floats(0, 1), min_size=len(AWAY_FROM_MOUTH), max_size=len(AWAY_FROM_MOUTH))
)
def test_a_face_without_collision_comes_back_unchanged_exactly(ict_model, values) -> None:
    w = ict_model.rig.weights_from_names(dict(zip(AWAY_FROM_MOUTH, values, strict=True)))[None]
    r = correct_faces(ict_model, w)
    assert not r.collided[0] and np.all(r.collision == 0)
    plain = ict_model.evaluate(w)
    corrected = evaluate_corrected(ict_model, w)
    if not r.changed()[0]:
        np.testing.assert_array_equal(corrected, plain)  # bit for bit
    else:  # only combinational correctives (their drivers were both on)
        assert np.any(r.combinational[0] > 0)


def test_ga_faces_without_collision_keep_zero_collision_weights_and_their_vertices(
    ict_model, ga_weights
) -> None:
    w = ga_weights[0][:120]
    r = correct_faces(ict_model, w)
    clean = ~r.collided
    assert clean.any() and (~clean).any()
    assert np.all(r.collision[clean] == 0)
    untouched = ~r.changed()
    if untouched.any():
        np.testing.assert_array_equal(
            evaluate_corrected(ict_model, w[untouched]), ict_model.evaluate(w[untouched])
        )
    # batch = one at a time
    one = correct_faces(ict_model, w[5:6])
    np.testing.assert_allclose(one.collision[0], r.collision[5], atol=1e-9)


def test_result_records_core_and_correctives_separately(ict_model, ict_correctives) -> None:
    w = ict_model.rig.weights_from_names(
        {"mouthShrugLower": 1.0, "mouthPress": 0.8, "eyeBlink": 0.5, "eyeLookDown": 0.5}
    )[None]
    r = correct_faces(ict_model, w)
    np.testing.assert_array_equal(r.core, w)
    assert r.collision.shape == (1, 8) and r.collided[0] and not r.remaining[0]
    assert r.corrective_names == ict_correctives.names
    i = ict_correctives.combinational_names.index("corr_eyeBlink_L_eyeLookDown_L")
    assert r.combinational[0, i] == pytest.approx(0.25)
    cols = r.columns()
    assert list(cols)[: ict_model.n_shapes] == list(ict_model.shape_names)
    assert "collision_lip_inner_left" in cols
    verts = evaluate_corrected(ict_model, w)
    expect = ict_model.evaluate(r.weights)[0] + np.einsum(
        "c,cvd->vd",
        r.correctives[0],
        np.concatenate([ict_correctives.combinational_deltas, ict_correctives.collision_deltas]),
    )
    np.testing.assert_allclose(verts[0], expect, atol=2e-5)


def test_correct_rejects_bad_weights(ict_model) -> None:
    with pytest.raises(ShapeError, match=r"\[0, 1\]"):
        correct_faces(ict_model, np.full((1, ict_model.n_shapes), 1.5))
    with pytest.raises(ShapeError, match="2-D"):
        correct_faces(ict_model, np.zeros(ict_model.n_shapes))


def test_identities_are_corrected_with_their_own_neutral(ict_model) -> None:
    w = ict_model.rig.weights_from_names({"mouthShrugLower": 1.0})[None]
    for identity in ("male", "female"):
        r = correct_faces(ict_model.with_identity(identity), w)
        assert r.collided[0] and not r.remaining[0]


def test_correctives_are_cached_on_disk(ict_model, ict_correctives) -> None:
    from emogen.correct import correctives as mod

    mod._MEMORY.clear()
    t = mod._cache_path(mod.cache_key(ict_model))
    assert t.is_file()
    again = mod.correctives_for(ict_model)
    assert again is not ict_correctives and again.key == ict_correctives.key
    np.testing.assert_array_equal(again.collision_deltas, ict_correctives.collision_deltas)
    np.testing.assert_array_equal(
        again.layout.anchor_bary[1], ict_correctives.layout.anchor_bary[1]
    )


def test_interpenetration_before_and_after_on_ga_faces(ict_model, ga_weights, mouth) -> None:
    """≥ 500 GA faces: the independent winding-number test before and after correction."""
    w, source = ga_weights
    assert len(w) >= 500 and set(source) == {"protocol", "random", "evolved"}
    test = Interpenetration.build(
        ict_model.base_neutral.astype(np.float64), ict_model.regions, mouth
    )
    assert not test.penetrating(ict_model.evaluate(np.zeros((1, ict_model.n_shapes))))[0]
    r = correct_faces(ict_model, w)
    before = test.penetrating(ict_model.evaluate(w, gaze=False))
    # every face the correctives changed (the reach shapes move lips without any collision)
    changed = np.flatnonzero(r.changed())
    after = before.copy()
    after[changed] = test.penetrating(corrected_vertices(ict_model, r, gaze=False)[changed])
    assert before.mean() > 0.2  # GA faces often collide: the test has something to find
    assert after.mean() <= 0.005, f"after correction {after.sum()} of {len(w)} faces interpenetrate"
    assert r.remaining.mean() <= 0.005


def test_a_faces_correction_does_not_depend_on_its_batch_or_the_blas_threads(
    ict_model, ga_weights
) -> None:
    """Exact replay needs a face's corrected weights to be a function of that face alone: the
    same bits corrected with 199 others, one at a time, in uneven slices, and with BLAS on one
    thread."""
    from threadpoolctl import threadpool_limits

    w = ga_weights[0][:200]
    whole = correct_faces(ict_model, w)
    assert whole.collided.sum() > 20
    for rows in ([slice(i, i + 1) for i in range(0, 200, 9)], [slice(3, 10), slice(10, 77)]):
        for s in rows:
            part = correct_faces(ict_model, w[s])
            np.testing.assert_array_equal(part.correctives, whole.correctives[s])
            np.testing.assert_array_equal(part.weights, whole.weights[s])
    with threadpool_limits(limits=1):
        np.testing.assert_array_equal(correct_faces(ict_model, w).correctives, whole.correctives)


def test_both_collision_solvers_correct_ga_faces_alike(ict_model, ga_weights) -> None:
    """Solver 2 (compiled rounds: jacobian and exact eq. 5 blocks) against solver 1 (numpy
    jacobian, scipy's BVLS) on 300 GA faces: the same detect–solve rounds, the same collisions
    left, and corrective weights equal to 1e-9 — and each solver is exactly repeatable."""
    w = ga_weights[0][:300]
    one = correct_faces(ict_model, w, solver=1)
    two = correct_faces(ict_model, w, solver=2)
    assert one.collided.sum() > 30
    np.testing.assert_array_equal(two.iterations, one.iterations)
    np.testing.assert_array_equal(two.within_after, one.within_after)
    np.testing.assert_allclose(two.collision, one.collision, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(correct_faces(ict_model, w, solver=2).collision, two.collision)
    with pytest.raises(ValueError, match="collision solver must be one of"):
        correct_faces(ict_model, w[:2], solver=0)


def test_the_compiled_loop_is_the_stepwise_loop_bit_for_bit(ict_model, ga_weights) -> None:
    """Solver 2's detect–solve loop compiled whole gives every output of the round-by-round
    Python loop (``detect`` and the compiled solve round per round) bit for bit, on 510 GA
    faces in batches of 9 (a study's generation) and at every iteration limit; a recorded
    study replays through either."""
    from emogen.correct.apply import Corrector
    from emogen.correct.blend import blend
    from emogen.correct.combinational import activations
    from emogen.correct.solve import DEPTH_MARGIN, _solve_stepwise, solve_collisions

    corrector = Corrector(ict_model)
    c = corrector.correctives
    eff = corrector.effective_weights(ga_weights[0])
    comb = activations(eff, c.drivers, c.driver_mask)
    base = blend(
        corrector._neutral, np.concatenate([eff, comb], axis=1), corrector._base_rows
    ).reshape(len(eff), -1, 3)
    deltas, layout = corrector._collision_local, c.layout
    fields = ("weights", "within_before", "within_after", "depth_after", "iterations")
    collided, rounds = 0, set()
    for start in range(0, len(base), 9):
        for limit in (6, 1, 0) if start < 90 else (6,):
            part = base[start : start + 9]
            fast = solve_collisions(part, deltas, layout, max_iterations=limit, solver=2)
            slow = _solve_stepwise(
                part, deltas, layout, max_iterations=limit, margin=DEPTH_MARGIN, solver=2
            )
            for name in fields:
                np.testing.assert_array_equal(getattr(fast, name), getattr(slow, name), name)
            collided += int(fast.collided.sum()) if limit == 6 else 0
            rounds |= set(fast.iterations.tolist())
    assert collided > 50 and {0, 1, 2} <= rounds  # colliding faces, several rounds
    empty = solve_collisions(base[:0], deltas, layout, solver=2)
    assert empty.weights.shape == (0, 8) and empty.iterations.shape == (0,)


def test_blend_is_start_plus_weights_times_rows_in_a_fixed_order() -> None:
    from emogen.correct.blend import blend

    rng = np.random.default_rng(0)
    rows = rng.normal(size=(6, 40))
    weights = rng.random((5, 6)) * (rng.random((5, 6)) > 0.4)
    start = rng.normal(size=(5, 40))
    loop = start.copy()
    for i in range(5):
        for k in range(6):
            if weights[i, k] != 0:
                loop[i] += weights[i, k] * rows[k]
    np.testing.assert_array_equal(blend(start, weights, rows), loop)
    np.testing.assert_allclose(blend(start[0], weights, rows), start[0] + weights @ rows)
    with pytest.raises(ValueError, match="start has 2 rows for 5 faces"):
        blend(start[:2], weights, rows)
    with pytest.raises(
        ValueError, match=r"weights \(B, K\), rows \(K, D\); got \(1, 40\), \(5, 6\)"
    ):
        blend(start[0], weights, rows[:5])
