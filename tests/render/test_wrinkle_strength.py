"""An identity's ``wrinkle_strength`` scales the strain wrinkles and folds, and nothing else.

The reference is the renderer's other path: faces drawn with no morph-target weights
(``render_vertices(..., targets=None)``) get no strain on the CPU and therefore no wrinkles.
"""

from __future__ import annotations

import numpy as np

from emogen.appearance.identities import PRESETS
from emogen.correct.faces import correct_faces, corrected_vertices
from emogen.render.renderer import Renderer

SIZE = 160


def _linear_luminance(images: np.ndarray) -> np.ndarray:
    c = images.astype(np.float64) / 255.0
    lin = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    return lin @ np.array([0.2126, 0.7152, 0.0722])


def test_wrinkle_strength_scales_the_furrows_and_leaves_unstrained_skin_alone(ict_model) -> None:  # type: ignore[no-untyped-def]
    """Anger (its glabellar furrows) and the neutral face on female-dark-v3's appearance at
    strength 0, 1 and 2: 0 is exactly the face without wrinkles; the neutral face, whose skin
    is unstrained, is the same at every strength; the angry face's wrinkle darkening (the
    luminance it loses against the wrinkle-free face) grows with the strength."""
    preset = PRESETS["female-dark-v3"]
    assert preset.appearance.wrinkle_strength == 2.0
    model = ict_model.with_identity(preset.shape)
    angry = model.rig.weights_from_names({g: 1.0 for g in model.rig.emotions["angry"].core})
    w = np.stack([np.zeros(model.n_shapes), angry]).astype(np.float32)
    result = correct_faces(model, w)
    vertices = corrected_vertices(model, result)
    targets = np.concatenate([result.weights, result.correctives], axis=1)
    images = {}
    with Renderer(model, size=SIZE, appearance=preset.appearance) as r:
        plain = r.render_vertices(vertices, targets=None).astype(int)
        images[2.0] = r.render_vertices(vertices, targets=targets).astype(int)
        for k in (0.0, 1.0):  # the same painted skin, only the uniform changed
            r._gl.set_wrinkle_strength(k)
            images[k] = r.render_vertices(vertices, targets=targets).astype(int)
    assert np.abs(images[0.0] - plain).max() <= 1
    for k in (1.0, 2.0):
        assert np.abs(images[k][0] - plain[0]).max() <= 1, k  # neutral: no strain, no wrinkles
    y_plain = _linear_luminance(plain[1])
    loss = {k: float((y_plain - _linear_luminance(images[k][1])).clip(0).sum()) for k in (1.0, 2.0)}
    assert loss[1.0] > 0.5  # the furrows are drawn at all (summed over ~25k skin pixels)
    assert loss[2.0] > 1.6 * loss[1.0], loss


def test_a_record_without_wrinkle_strength_replays_with_the_old_look() -> None:
    """Identities recorded before the parameter existed rebuild with strength 1 — the shading
    of every earlier version — and the -v2 presets keep it."""
    record = PRESETS["male-dark-v2"].appearance.record()
    assert record.pop("wrinkle_strength") == 1.0
    assert type(PRESETS["male-dark-v2"].appearance)(**record) == PRESETS["male-dark-v2"].appearance
