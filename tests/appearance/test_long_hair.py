"""``hair = "long"``: a layer of long hair over the ``face`` framing (emogen.appearance.long_hair).

The layer is fixed per identity while the face moves, so the checks that matter are that it
leaves every expression visible (the landmarks of the prototypes and of the extreme brow raise
and jaw drop lie where it is clear), that it is there (hair beside the face), that the short-haired
presets are untouched (recorded studies replay), and that bad values are named.
"""

from __future__ import annotations

import numpy as np
import pytest

from emogen.appearance.identities import PRESETS, identity_from_dict
from emogen.appearance.long_hair import (
    LAYER_PX,
    apply_layer,
    decode_layer,
    identity_layer,
    layer_webp,
    long_hair_layer,
    resample_layer,
)
from emogen.errors import ConfigError
from emogen.render.look import default_look, fitted_look

LONG = ("female-light-long", "female-medium-long", "female-dark-v3-long")


@pytest.fixture(scope="module")
def layers(ict_model):  # type: ignore[no-untyped-def]
    """Per long preset: (model, camera, layer at LAYER_PX)."""
    out = {}
    for name in LONG[::2]:  # light and dark-v3: the two hair colours
        ident = PRESETS[name]
        model = ict_model.with_identity(ident.shape)
        camera = fitted_look(default_look(), model, ident.appearance).camera
        out[name] = (model, camera, identity_layer(model, ident.appearance, camera))
    return out


def _extreme_faces(model) -> np.ndarray:  # type: ignore[no-untyped-def]
    rig = model.rig
    rows = [rig.weights_from_names({g: 1.0 for g in rig.emotions[e].core}) for e in rig.emotions]
    raise_all = {f"brow{s}Up_{side}": 1.0 for s in ("Inner", "Outer") for side in "LR"}
    rows.append(rig.weights_from_names({"jawOpen": 1.0, **raise_all}))
    rows.append(
        rig.weights_from_names({"jawOpen": 1.0, "mouthStretch_L": 1.0, "mouthStretch_R": 1.0})
    )
    rows.append(np.zeros(model.n_shapes))
    return np.asarray(rows)


def test_the_layer_leaves_every_expression_visible(layers) -> None:  # type: ignore[no-untyped-def]
    """At the landmarks of the brows, eyes, nose and mouth (17-67) of every emotion prototype,
    a full brow raise with the jaw dropped and a full lip stretch, the layer is clear (no hair,
    no shadow: alpha ≤ 2/255); at the lower jaw and chin (5-11) it is mostly clear even with the
    jaw fully dropped. Landmarks from the model's own moved vertices, projected by the camera."""
    for name, (model, camera, layer) in layers.items():
        verts = model.evaluate(_extreme_faces(model))
        alpha = layer[..., 3].astype(int)
        for i, face in enumerate(verts):
            px = camera.project(face[model.landmarks], LAYER_PX)
            col, row = np.floor(px).astype(int).T
            assert np.all((col >= 0) & (col < LAYER_PX) & (row >= 0) & (row < LAYER_PX)), name
            inner = alpha[row[17:], col[17:]]
            assert inner.max() <= 2, (name, i, int(np.argmax(inner)) + 17, inner.max())
            jaw = alpha[row[5:12], col[5:12]]
            assert jaw.max() < 128, (name, i, jaw.tolist())


def test_hair_frames_the_face(layers) -> None:  # type: ignore[no-untyped-def]
    """Opaque hair beside the face at the ears' height and beside the neck on both sides, of the
    preset's hair colour (mean within 40 levels of it), and none at the centre of the face."""
    from emogen.appearance.params import hex_to_srgb

    for name, (model, camera, layer) in layers.items():
        from emogen.appearance.features import face_features

        lm = camera.project(face_features(model).landmarks, LAYER_PX)
        half = (lm[16, 0] - lm[0, 0]) / 2
        for k, side in ((0, -1), (16, 1)):
            for y in (lm[k, 1], lm[8, 1] + 0.3 * half):
                x = int(lm[k, 0] + side * 0.2 * half)
                assert layer[int(y), x, 3] == 255, (name, k, y)
        hair = layer[..., 3] == 255
        colour = 255 * np.array(hex_to_srgb(PRESETS[name].appearance.hair_colour))
        assert np.abs(layer[hair][:, :3].mean(0) - colour).max() < 40, name
        nose = np.floor(lm[30]).astype(int)
        assert layer[nose[1], nose[0], 3] == 0
        # the hair has strands: its luminance varies across the curtain
        assert layer[hair][:, :3].astype(float).mean(1).std() > 2.0, name


def test_resample_is_the_premultiplied_box_mean() -> None:
    """resample_layer halves a layer as a plain loop over 2×2 blocks of premultiplied colour."""
    rng = np.random.default_rng(3)
    layer = rng.integers(0, 256, (16, 16, 4), dtype=np.uint8)
    half = resample_layer(layer, 8).astype(float)
    for r in range(8):
        for c in range(8):
            block = layer[2 * r : 2 * r + 2, 2 * c : 2 * c + 2].reshape(4, 4).astype(float)
            a = block[:, 3] / 255
            alpha = a.mean()
            assert abs(half[r, c, 3] - 255 * alpha) <= 0.5 + 1e-6
            if alpha > 0.05:
                rgb = (block[:, :3] * a[:, None]).mean(0) / alpha
                assert np.all(np.abs(half[r, c, :3] - rgb) <= 0.5 + 1e-6), (r, c)


def test_apply_layer_is_over_in_srgb() -> None:
    """Each pixel: image × (1 − α) + layer × α, rounded (a plain per-pixel loop)."""
    rng = np.random.default_rng(4)
    images = rng.integers(0, 256, (2, 6, 6, 3), dtype=np.uint8)
    layer = rng.integers(0, 256, (6, 6, 4), dtype=np.uint8)
    out = apply_layer(images, layer)
    for n in range(2):
        for r in range(6):
            for c in range(6):
                a = layer[r, c, 3] / 255
                want = images[n, r, c] * (1 - a) + layer[r, c, :3] * a
                assert np.all(np.abs(out[n, r, c] - want) <= 0.5 + 1e-4)


def test_the_webp_bytes_keep_the_alpha_and_are_small(layers) -> None:  # type: ignore[no-untyped-def]
    """The bytes both renderers decode: alpha exact (lossless), colour within a few levels where
    there is hair, and small enough for the GLB's budget (< 0.3 MB)."""
    _, _, layer = layers["female-light-long"]
    data = layer_webp(layer)
    assert len(data) < 300_000, len(data)
    back = decode_layer(data)
    assert np.array_equal(back[..., 3], layer[..., 3])
    hair = layer[..., 3] == 255
    assert np.abs(back[hair][:, :3].astype(int) - layer[hair][:, :3]).mean() < 3.0


def test_short_haired_presets_are_unchanged() -> None:
    """Every preset that existed before keeps hair 'short' (its studies replay with the same
    faces); the long presets differ from their short twins in ``hair`` alone."""
    for name, ident in PRESETS.items():
        if not name.endswith("-long"):
            assert ident.appearance.hair == "short", name
    for name in LONG:
        twin = PRESETS[name.removesuffix("-long")]
        assert PRESETS[name].shape == twin.shape
        a, b = PRESETS[name].appearance.record(), twin.appearance.record()
        assert {k for k in a if a[k] != b[k]} == {"hair"}, name


def test_a_short_haired_renderer_has_no_layer(ict_model) -> None:  # type: ignore[no-untyped-def]
    from emogen.render.renderer import Renderer

    ident = PRESETS["female-light"]
    with Renderer(ict_model.with_identity(ident.shape), size=64, appearance=ident.appearance) as r:
        assert r.hair_layer is None


def test_bad_values_are_named() -> None:
    with pytest.raises(ConfigError, match=r"'hair'.*'longg'"):
        identity_from_dict("lab", {"shape": "female", "hair": "longg"})
    with pytest.raises(ValueError, match="68 finite"):
        long_hair_layer(np.zeros((5, 2)), 64, "#202020")
    with pytest.raises(ValueError, match="at least 16 pixels"):
        long_hair_layer(np.zeros((68, 2)), 8, "#202020")
    with pytest.raises(ValueError, match=r"right edge \(16\)"):
        long_hair_layer(np.zeros((68, 2)), 64, "#202020")
    with pytest.raises(ValueError, match="hair_colour"):
        lm = np.tile(np.linspace(10, 50, 68)[:, None], (1, 2))
        long_hair_layer(lm, 64, "brown")
    with pytest.raises(ValueError, match=r"does not fit images of shape \(1, 8, 8, 3\)"):
        apply_layer(np.zeros((1, 8, 8, 3), np.uint8), np.zeros((4, 4, 4), np.uint8))


def test_a_study_names_it_and_its_export_records_it() -> None:
    """A study's identities include the long presets and a lab's own ``hair = "long"``; the
    export's ``identities`` table records ``hair`` per identity, and reading the table back
    rebuilds the same identities (replay: what was shown is what is re-rendered)."""
    import json
    from types import SimpleNamespace

    import pandas as pd

    from emogen.study.config import study_from_dict
    from emogen.study.export import identities_from_table, identity_rows

    config = study_from_dict(
        {
            "identities": ["female-dark-v3-long", "male-light", "lab_face"],
            "identity": {"lab_face": {"shape": "female", "skin_tone": 4.0, "hair": "long"}},
        }
    )
    study = SimpleNamespace(
        name="s",
        config_json=json.dumps(config.model_dump(mode="json")),
        package_version="x",
        model_hash="m",
        config_hash="c",
    )
    rows = identity_rows(study)  # type: ignore[arg-type]
    assert {r["identity"]: r["hair"] for r in rows} == {
        "female-dark-v3-long": "long",
        "male-light": "short",
        "lab_face": "long",
    }
    back = identities_from_table(pd.DataFrame(rows))
    assert back[("s", "female-dark-v3-long")] == PRESETS["female-dark-v3-long"]
    assert back[("s", "lab_face")].appearance.hair == "long"
