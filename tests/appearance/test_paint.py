"""The painted skin: features land where the geometry says, for every preset and any parameters.

References are independent of the painter: the brow and mouth shapes' own vertex motion (from
the model's OBJ deltas), the UV triangles' shoelace areas, the published Monk swatches.
"""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from emogen.appearance import Appearance
from emogen.appearance.features import brow_motion, face_features
from emogen.appearance.identities import PRESETS
from emogen.appearance.layout import skin_layout, skin_triangles
from emogen.appearance.paint import brow_coverage, lip_mask, monk_linear, srgb_to_linear
from emogen.appearance.params import MONK_SWATCHES, hex_to_srgb
from emogen.appearance.textures import texel_size_cm, texels

HEIGHT = 512
LIP_SHAPES = ("mouthRollUpper", "mouthRollLower", "mouthFunnel", "mouthPucker")


@cache
def _prepared(model, shape):  # type: ignore[no-untyped-def]
    m = model.with_identity(shape)
    layout = skin_layout(m, HEIGHT)
    feats = face_features(m)
    t = texels(m, layout, feats)
    corners = layout.triangles[layout.texel_tri.reshape(-1)[t.index]]
    names = list(m.shape_names)
    lip_motion = sum(np.linalg.norm(m.deltas[names.index(s)], axis=1) for s in LIP_SHAPES)
    return m, layout, feats, t, corners, brow_motion(m), lip_motion


@pytest.mark.parametrize("name", sorted(PRESETS))
def test_brows_and_lips_sit_on_the_moving_skin_of_every_preset(ict_model, name) -> None:  # type: ignore[no-untyped-def]
    identity = PRESETS[name]
    _check_features(ict_model, identity.shape, identity.appearance)


@settings(
    max_examples=6, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    shape=st.sampled_from(["generic", "male", "female"]),
    thickness=st.floats(0.5, 2.0),
    density=st.floats(0.3, 2.0),
    lip=st.floats(0.2, 1.5),
    seed=st.integers(0, 2**32 - 1),
)
def test_brows_and_lips_sit_on_the_moving_skin_for_any_parameters(  # type: ignore[no-untyped-def]
    ict_model, shape, thickness, density, lip, seed
) -> None:
    look = Appearance(brow_thickness=thickness, brow_density=density, lip_colour=lip, seed=seed)
    _check_features(ict_model, shape, look)


def _check_features(model, shape, look: Appearance) -> None:  # type: ignore[no-untyped-def]
    m, _, feats, t, corners, motion, lip_motion = _prepared(model, shape)
    face = m.regions["face"].vertices
    px = texel_size_cm(t)
    brow = brow_coverage(t, feats, look, np.random.default_rng(look.seed), px)
    dense = brow > 0.5
    assert dense.sum() > 100  # a brow pair is there, not a few stray texels
    # every vertex of every brow texel's triangle moves with the brow shapes: ≥ 0.5 cm at unit
    # weight, where the face's median vertex moves 0.06 cm
    assert np.median(motion[face]) < 0.1
    assert motion[corners[dense]].min() > 0.5
    # both brows, one each side of the midline, above the eyes
    assert (t.pos[dense, 0] > 0).any() and (t.pos[dense, 0] < 0).any()
    assert t.pos[dense, 1].min() > feats.eye_centres[:, 1].max()
    cover, _ = lip_mask(t, feats, px)
    lips = cover > 0.5
    assert lips.sum() > 1000
    assert np.median(lip_motion[face]) < 0.1
    assert lip_motion[corners[lips]].min() > 1.0  # the lips' own skin: rolled by the lip shapes


def test_every_texel_of_an_island_is_covered_once(ict_model) -> None:  # type: ignore[no-untyped-def]
    """Covered texels ≈ the UV triangles' total area (shoelace) in texels, and each covered
    texel's barycentric weights rebuild its own centre from its triangle's UVs."""
    layout = skin_layout(ict_model, HEIGHT)
    _, uv_ids = skin_triangles(ict_model)
    uv = ict_model.uvs[uv_ids].astype(np.float64)
    x = uv[..., 0] / 2 * layout.width
    y = (1 - uv[..., 1]) * layout.height
    area = 0.5 * np.abs(
        (x[:, 1] - x[:, 0]) * (y[:, 2] - y[:, 0]) - (x[:, 2] - x[:, 0]) * (y[:, 1] - y[:, 0])
    )
    assert layout.covered.sum() == pytest.approx(area.sum(), rel=0.02)
    rng = np.random.default_rng(0)
    rows, cols = np.nonzero(layout.covered)
    pick = rng.choice(len(rows), 2000, replace=False)
    for i, j in zip(rows[pick], cols[pick], strict=True):
        k = layout.texel_tri[i, j]
        b = layout.bary[i, j].astype(np.float64)
        assert b.min() >= -1e-5 and b.sum() == pytest.approx(1.0, abs=1e-5)
        assert b @ x[k] == pytest.approx(j + 0.5, abs=1e-3)
        assert b @ y[k] == pytest.approx(i + 0.5, abs=1e-3)


def test_monk_tones_are_the_published_swatches() -> None:
    for k, hexcode in enumerate(MONK_SWATCHES, start=1):
        expected = srgb_to_linear(np.array(hex_to_srgb(hexcode)))
        assert monk_linear(float(k)) == pytest.approx(expected)
    mid = monk_linear(5.5)
    assert np.all(mid <= np.maximum(monk_linear(5), monk_linear(6)) + 1e-12)
    assert np.all(mid >= np.minimum(monk_linear(5), monk_linear(6)) - 1e-12)


def test_lip_depth_darkens_the_vermilion_and_nothing_else(ict_model) -> None:  # type: ignore[no-untyped-def]
    """0.2 makes the lip texels 0.8 × as bright where the vermilion fully covers (lip colour 1:
    the texel is the vermilion's colour), and leaves every
    texel outside the lip outline as it was."""
    from emogen.appearance.paint import paint_albedo

    _, _, feats, t, _, _, _ = _prepared(ict_model, "male")
    px = texel_size_cm(t)
    look = PRESETS["male-dark"].appearance.model_copy(update={"lip_colour": 1.0})
    before = paint_albedo(t, feats, look, 1.0, px)
    deep = paint_albedo(t, feats, look.model_copy(update={"lip_depth": 0.2}), 1.0, px)
    cover, _ = lip_mask(t, feats, px)
    outside = cover == 0
    assert outside.sum() > 0.9 * len(cover)
    assert np.array_equal(deep[outside], before[outside])
    # full coverage, unclipped: the texel's colour is the vermilion's × 0.8
    full = (cover >= 1.0) & (before.max(axis=1) < 0.99)
    assert full.sum() > 1000
    np.testing.assert_allclose(deep[full], before[full] * 0.8, rtol=1e-6, atol=1e-9)
