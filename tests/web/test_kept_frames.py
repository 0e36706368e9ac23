"""Frames rendered ahead and kept (viewer/kept.js) in Debian's Chromium (SwiftShader): a face
shown from its kept frame is, pixel for pixel, the face the live WebGL draw shows for the same
weights, while the frames are still being drawn ahead and after all are kept; the kept frames
stay within their memory bound (the ones nearest the face shown), and forgetting them shows
the live draw again. The reference is the viewer's live draw of each face, screenshotted before
any frame was kept (test_viewer.py checks the live draw against the offscreen renderer)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from tests.web import viewer_site as vs
from tests.web.test_viewer import open_viewer, screenshot, weights_of

pytestmark = [pytest.mark.browser, pytest.mark.slow]

viewer_build = vs.viewer_build
viewer_site = vs.viewer_site
chromium = vs.chromium


@pytest.fixture(scope="module")
def site(viewer_site: vs.Site) -> vs.Site:
    return viewer_site


# The faces of a slider: the jaw opening in ``n`` steps under a half smile, the eyes looking
# left (their gaze is the viewer's own rotation, kept in the frame too).
def slider(model: Any, n: int) -> list[list[float]]:  # type: ignore[no-untyped-def]
    named = [{"jawOpen": k / (n - 1), "mouthSmile": 0.5, "eyeLookLeft": 0.6} for k in range(n)]
    return weights_of(model, *named)


# Whether face 0's kept frames are all drawn (none left to draw ahead, every copy made).
COMPLETE = """() => {
  const v = window.emogen.view, kept = v.kept.get(0);
  return kept.complete(kept.find(v.faces[0].shown));
}"""
# Count the WebGL draws from now on (window.liveDraws).
COUNT_DRAWS = """() => {
  const r = window.emogen.view.renderer;
  window.liveDraws = 0;
  if (!r.counted) {
    const render = r.render.bind(r);
    r.render = (...a) => { window.liveDraws += 1; return render(...a); };
    r.counted = true;
  }
}"""


def show(page: Any, weights: list[float]) -> np.ndarray:
    page.evaluate("w => window.emogen.setFaces([w])", weights)
    return screenshot(page.locator(".face").first)


def test_a_kept_frame_is_the_live_draw_of_its_face(chromium: Any, site: Any, ict_model) -> None:  # type: ignore[no-untyped-def]
    context, page, _ = open_viewer(chromium, site, "?faces=1&size=445")
    faces = slider(ict_model, 11)
    picks = [0, 3, 7, 10]
    live = {k: show(page, faces[k]) for k in picks}  # nothing kept yet: every one drawn live
    for a in picks:  # the faces differ, so equality below means the right face
        for b in picks:
            if a < b:
                assert (np.abs(live[a].astype(int) - live[b]).max(-1) > 20).sum() > 200, (a, b)
    page.evaluate("w => window.emogen.view.keep(0, w)", faces)
    # while frames are drawn ahead (the WebGL canvas drawing other faces under the one shown),
    # every face shown is its own: moved quickly, with kept and not-yet-kept positions
    for k in [0, 7, 3, 10, 0, 7]:
        assert np.array_equal(show(page, faces[k]), live[k]), k
    page.wait_for_function(COMPLETE, timeout=120_000, polling=100)
    assert page.evaluate("window.emogen.view.kept.get(0).frames.size") == 11
    page.evaluate(COUNT_DRAWS)
    for k in [10, 3, 0, 7, 3]:
        assert np.array_equal(show(page, faces[k]), live[k]), k
    assert page.evaluate("window.liveDraws") == 0  # all played from kept frames
    # forgotten (the trial is over): the live draw shows the face again, and draws on
    page.evaluate("() => window.emogen.view.keep(0, null)")
    assert page.evaluate("window.emogen.view.kept.size") == 0
    assert np.array_equal(screenshot(page.locator(".face").first), live[3])
    assert np.array_equal(show(page, faces[10]), live[10])
    assert page.evaluate("window.liveDraws") >= 2
    context.close()


def test_kept_frames_stay_within_their_memory_bound(chromium: Any, site: Any, ict_model) -> None:  # type: ignore[no-untyped-def]
    """1024 pixels at 2 device pixels a pixel: 16.8 MB a frame, so 128 MiB keeps 8 of 11, the
    ones nearest the face shown; moving the face keeps the ones nearest it instead."""
    context, page, _ = open_viewer(chromium, site, "?faces=1&size=1024", scale=2)
    faces = slider(ict_model, 11)
    live = {k: show(page, faces[k]) for k in (0, 10)}
    page.evaluate("w => window.emogen.view.keep(0, w)", faces)
    page.wait_for_function(COMPLETE, timeout=180_000, polling=200)
    kept = "() => [...window.emogen.view.kept.get(0).frames.keys()].sort((a, b) => a - b)"
    limit = (128 * 2**20) // (2048 * 2048 * 4)
    assert page.evaluate("window.emogen.view.kept.get(0).limit") == limit == 8
    assert page.evaluate(kept) == list(range(11 - limit, 11))  # the face shown: position 10
    assert np.array_equal(show(page, faces[0]), live[0])  # not kept: drawn live, then kept
    page.wait_for_function(COMPLETE, timeout=180_000, polling=200)
    assert page.evaluate(kept) == list(range(limit))
    assert np.array_equal(show(page, faces[0]), live[0])
    context.close()
