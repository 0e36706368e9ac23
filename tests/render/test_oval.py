"""The oval framing's mask against an independent reference: pixel coverage counted on a fine
grid of sample points inside the ellipse."""

from __future__ import annotations

import numpy as np

from emogen.render.images import apply_oval, oval_coverage

OVAL = (0.5, 0.47, 0.30, 0.43)


def test_coverage_matches_point_counting() -> None:
    size, k = 64, 16
    sub = (np.arange(size * k) + 0.5) / (size * k)
    x, y = np.meshgrid(sub, sub)
    inside = ((x - OVAL[0]) / OVAL[2]) ** 2 + ((y - OVAL[1]) / OVAL[3]) ** 2 <= 1
    counted = inside.reshape(size, k, size, k).mean(axis=(1, 3))
    cover = oval_coverage(size, OVAL)
    assert np.abs(cover - counted).max() < 0.12
    assert abs(cover.sum() - np.pi * OVAL[2] * OVAL[3] * size**2) < 0.01 * cover.sum()


def test_outside_is_background_inside_is_the_face() -> None:
    rng = np.random.default_rng(0)
    images = rng.integers(0, 256, (2, 64, 64, 3), dtype=np.uint8)
    out = apply_oval(images, OVAL, (0.5, 0.5, 0.5))
    assert np.all(out[:, 0, 0] == 128) and np.all(out[:, :, :4] == 128)
    assert np.array_equal(out[:, 30, 32], images[:, 30, 32])
