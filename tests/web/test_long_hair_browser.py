"""``hair = "long"`` in Debian's Chromium: the identity's GLB carries its long-hair layer (WebP),
the viewer lays it over each face, and the page agrees with the offscreen renderer, which
composites the same decoded bytes (emogen.appearance.long_hair), within the limits of
test_viewer.py — for the neutral face and for the extremes the layer must not hide (a full brow
raise with the jaw dropped). Under ``oval`` framing the oval lies over the hair, as offscreen.
The check can fail: the page with its hair layer taken away is far from the offscreen face."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from tests.web import viewer_site as vs
from tests.web.test_viewer import (
    MAX_MEAN_ABS,
    assert_agrees,
    open_viewer,
    screenshot,
    weights_of,
)

pytestmark = pytest.mark.browser

viewer_build = vs.viewer_build
viewer_site = vs.viewer_site
chromium = vs.chromium
Site = vs.Site

NAME = "female-dark-v3-long"


@pytest.fixture(scope="module")
def site(viewer_site: Site, ict_model) -> Site:  # type: ignore[no-untyped-def]
    vs.export_site_glb(ict_model, viewer_site.folder / f"{NAME}.glb", NAME)
    return viewer_site


def _faces(ict_model) -> np.ndarray:  # type: ignore[no-untyped-def]
    raise_all = {f"brow{s}Up_{side}": 1.0 for s in ("Inner", "Outer") for side in "LR"}
    return np.array(weights_of(ict_model, {}, {"jawOpen": 1.0, **raise_all}))


@pytest.mark.parametrize("framing", ["face", "oval"])
def test_long_hair_agrees_with_offscreen(
    chromium: Any, site: Site, ict_model, framing: str
) -> None:  # type: ignore[no-untyped-def]
    from emogen.render.gl import downsample

    w = _faces(ict_model)
    query = f"?faces=1&size=512&columns=1&model={NAME}.glb"
    if framing == "oval":
        query += "&framing=oval"
    context, page, _ = open_viewer(chromium, site, query, width=600, scale=2)
    with vs.offscreen_renderer(ict_model, 512, name=NAME, supersample=2, framing=framing) as r:
        assert r.hair_layer is not None
        offscreen = r.render(w).astype(int)
    slot = page.locator(".face").first
    assert page.locator(".face .hair-layer").count() == 1
    for i in range(len(w)):
        page.evaluate("w => window.emogen.setFaces([w])", w[i].tolist())
        shot = downsample(screenshot(slot), 2).astype(int)
        assert_agrees(shot, offscreen[i], i)
    if framing == "face":
        page.evaluate("document.querySelector('.hair-layer').remove()")
        bare = downsample(screenshot(slot), 2).astype(int)
        assert np.abs(bare - offscreen[-1]).mean() > 10 * MAX_MEAN_ABS
    context.close()
