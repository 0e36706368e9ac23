"""The face framing and the texture cache."""

from __future__ import annotations

import numpy as np
import pytest

from emogen.appearance import Appearance
from emogen.appearance.framing import face_span
from emogen.appearance.identities import PRESETS
from emogen.appearance.textures import skin_textures
from emogen.render.look import default_look, fitted_look

SIZE = 512


@pytest.mark.parametrize("name", sorted(PRESETS))
def test_face_framing_fills_80_percent_and_keeps_an_open_jaw(ict_model, name) -> None:  # type: ignore[no-untyped-def]
    ident = PRESETS[name]
    m = ict_model.with_identity(ident.shape)
    look = fitted_look(default_look(), m, ident.appearance)
    hair, chin, depth = face_span(m, ident.appearance)
    rows = look.camera.project(np.array([[0.0, hair, depth], [0.0, chin, depth]]), SIZE)[:, 1]
    assert (rows[1] - rows[0]) / SIZE >= 0.80
    assert rows[0] >= 0  # the hairline is in the picture
    # the chin of a fully open jaw (with the mouth stretched down) stays inside the image
    w = m.rig.weights_from_names({"jawOpen": 1.0, "mouthLowerDown": 1.0})[None]
    lowest = m.evaluate(w)[0][m.regions["face"].vertices]
    front = lowest[:, 2] > depth - 3
    chin_open = lowest[front][np.argmin(lowest[front, 1])]
    assert look.camera.project(chin_open[None], SIZE)[0, 1] < SIZE


def test_head_framing_is_the_fixed_camera(ict_model) -> None:  # type: ignore[no-untyped-def]
    look = default_look().with_options(framing="head")
    assert fitted_look(look, ict_model, None).camera == look.framings["head"]


def test_textures_are_cached_and_a_corrupt_cache_is_rebuilt(
    ict_model, tmp_path, monkeypatch
) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.setenv("EMOGEN_CACHE_DIR", str(tmp_path))
    look = Appearance(skin_tone=7, seed=3)
    first = skin_textures(ict_model, look, irradiance=1.0, height=256)
    files = sorted((tmp_path / "appearance").glob("skin-*.webp"))
    assert len(files) == 1
    files[0].write_bytes(first.albedo_webp[:100])  # truncated
    again = skin_textures(ict_model, look, irradiance=1.0, height=256)
    assert again.albedo_webp == first.albedo_webp
    assert np.array_equal(again.albedo, first.albedo)
    other = skin_textures(ict_model, Appearance(skin_tone=2, seed=3), irradiance=1.0, height=256)
    assert other.key != first.key
    # a darker tone paints a darker atlas
    assert other.albedo.mean() > first.albedo.mean() + 30


@pytest.mark.parametrize("tone", [2, 5, 8])
def test_a_lit_cheek_renders_at_its_monk_swatch(ict_model, tone) -> None:  # type: ignore[no-untyped-def]
    """Known answer: the generator divides the swatch by the frontal light, so a frontal cheek
    (no regional redness) comes out at the published swatch, within a few levels (the specular
    sheen, additive, lifts the darkest tones a little more)."""
    from emogen.appearance.params import MONK_SWATCHES, hex_to_srgb
    from emogen.render.renderer import Renderer

    with Renderer(ict_model, size=256, appearance=Appearance(skin_tone=tone, redness=0)) as r:
        image = r.render(np.zeros((1, ict_model.n_shapes)))[0].astype(float)
        lm = ict_model.neutral[ict_model.landmarks]
        cheek = (lm[41] + lm[31]) / 2 + np.array([-0.5, -0.3, 0.0])
        x, y = r.look.camera.project(cheek[None], 256)[0].astype(int)
    patch = image[y - 2 : y + 3, x - 2 : x + 3].reshape(-1, 3).mean(0)
    swatch = np.array(hex_to_srgb(MONK_SWATCHES[tone - 1])) * 255
    assert np.abs(patch - swatch).max() < (8 if tone < 6 else 20)
    assert np.abs(patch - np.array(hex_to_srgb(MONK_SWATCHES[tone + 1])) * 255).max() > 20
