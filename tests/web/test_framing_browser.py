"""A study with ``framing = "oval"`` shows its participants every face through look.json's
oval, in Debian's Chromium (Playwright): the 3D viewer's tiles and the rating face, the
server's PNGs for browsers without WebGL, and the jsPsych plugin's categorise face. Outside the oval a tile is the background colour
(128, 128, 128) to the pixel; the same tile with the oval layer taken away shows hair, ears and
neck there, so the oval hides what the ``face`` framing shows. The session still replays (the
framing is appearance, not GA state) and the export records the framing.
"""

from __future__ import annotations

import io
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from benchmarks.bench_study import ServerProcess, write_study_toml
from benchmarks.jspsych_site import ExperimentSite, build_plugin, one_trial_page
from PIL import Image

from emogen.render.look import default_look
from emogen.study.export import export_tables
from emogen.study.replay import replay_session
from emogen.study.storage import Store
from tests.web.test_devices import start
from tests.web.test_jspsych_browser import open_page, serve, wait_stage
from tests.web.test_study_browser import CSP_PROBE, browser, viewer_bundle, wait_ready

pytestmark = [pytest.mark.browser, pytest.mark.slow]
_ = (browser, viewer_bundle)  # fixtures, requested by name

OVAL_STUDY: dict[str, Any] = {
    "name": "oval",
    "emotions": ["happy"],
    "order": "fixed",
    "seed": 7,
    "framing": "oval",
    "ga": {"generations": 1, "min_selections": 1, "max_selections": 2},
    "completion": {"code": "OVAL-OK"},
}
SCREENSHOTS = Path("/tmp/emogen-framing-screenshots")
BACKGROUND = 128  # look.json's background_srgb 0.5, as the page and the PNGs write it


@pytest.fixture(scope="module")
def site(
    tmp_path_factory: pytest.TempPathFactory, ict_dir: Path, ict_model, viewer_bundle: Path
) -> Iterator[tuple[ServerProcess, str]]:  # type: ignore[no-untyped-def]
    tmp = tmp_path_factory.mktemp("framing")
    db = f"sqlite:///{tmp / 'study.sqlite'}"
    config = write_study_toml(OVAL_STUDY, tmp / "oval.toml")
    srv = ServerProcess(config, db, ict_dir, tmp / "server.log")
    yield srv.start(), db
    srv.stop()


def outside_oval(shape: tuple[int, ...], margin: float = 0.08) -> np.ndarray:
    """Pixels of a square tile clearly outside look.json's oval (its edge ± ``margin``), less
    the tile's rounded corners (12 px: the page's border-radius shows the page there)."""
    cx, cy, rx, ry = default_look().ovals["oval"]
    h, w = shape[:2]
    rows, cols = np.mgrid[0:h, 0:w]
    v, u = (rows + 0.5) / h, (cols + 0.5) / w
    near = lambda i, n: (i < 12) | (i >= n - 12)  # noqa: E731
    corner = near(rows, h) & near(cols, w)
    return (((u - cx) / rx) ** 2 + ((v - cy) / ry) ** 2 > 1 + margin) & ~corner  # type: ignore[no-any-return]


def tile(locator: Any) -> np.ndarray:
    """What the participant sees of one face: its slot's pixels on the screen (RGB), less a
    one-pixel frame (a box at a fractional position takes in a row of the page around it)."""
    shot = Image.open(io.BytesIO(locator.screenshot())).convert("RGB")
    return np.asarray(shot, dtype=int)[1:-1, 1:-1]


def marks(page: Any, visibility: str) -> None:
    """The faces' numbers, badges and stars (drawn over the tiles on purpose) hidden or shown."""
    page.evaluate(
        "v => document.querySelectorAll('.num, .badge, .star')"
        ".forEach(e => { e.style.visibility = v; })",
        visibility,
    )


def off_background(pixels: np.ndarray) -> np.ndarray:
    return np.abs(pixels - BACKGROUND).max(axis=-1)  # type: ignore[no-any-return]


def test_oval_study_shows_faces_through_the_oval(
    site: tuple[ServerProcess, str], browser: Any, ict_model: Any
) -> None:
    server, db = site
    page = start(browser, server, (1366, 768), "oval-1")  # a page error fails the test
    page.context.add_init_script(CSP_PROBE)  # the oval layer is styled within the page's CSP
    page.reload()
    wait_ready(page, "instructions")
    page.get_by_role("button", name="Begin").click()
    wait_ready(page, "trial")
    assert page.evaluate("window.emogenStudy.display") == "webgl"
    SCREENSHOTS.mkdir(exist_ok=True)
    page.screenshot(path=str(SCREENSHOTS / "oval-trial-1366x768.png"))

    slots = page.locator("#grid > .cell .slot")
    assert slots.count() == 10
    marks(page, "hidden")
    for k in (0, 4, 9):
        pixels = tile(slots.nth(k))
        out = outside_oval(pixels.shape)
        assert off_background(pixels[out]).max() <= 2, f"tile {k}: the face shows outside the oval"
        inside = off_background(pixels[~outside_oval(pixels.shape, -0.4)])
        assert (inside > 10).mean() > 0.9, f"tile {k}: no face inside the oval"
    # the same tile without the oval layer: the face framing's hair, ears and neck are there
    layer = "document.querySelector('#grid .slot .oval-layer').style.visibility"
    page.evaluate(f"{layer} = 'hidden'")
    bare = tile(slots.nth(0))
    assert (off_background(bare[outside_oval(bare.shape)]) > 10).mean() > 0.1
    page.evaluate(f"{layer} = ''")
    marks(page, "")

    for _ in range(2):  # rounds 1 and 2, then the rating's face
        page.click("#grid > .cell:nth-child(3) .face")
        page.click("#next")
        wait_ready(page, "trial" if _ == 0 else "rating")
    page.screenshot(path=str(SCREENSHOTS / "oval-rating-1366x768.png"))
    rated = tile(page.locator("#rating-slot"))
    Image.fromarray(rated.astype(np.uint8)).save(SCREENSHOTS / "oval-rating-slot.png")
    assert off_background(rated[outside_oval(rated.shape)]).max() <= 2
    page.get_by_label("5", exact=True).check()
    page.click("#rate")
    wait_ready(page, "done")
    assert page.evaluate("window.__cspViolations") == []
    page.context.close()

    # the framing is appearance: the session replays; the export says what participants saw
    store = Store(db)
    try:
        assert replay_session(store, 1, ict_model.rig, ict_model.model_hash, model=ict_model).ok
        study = export_tables(store)["study"]
        assert study.framing.tolist() == ["oval"]
    finally:
        store.dispose()


def test_oval_study_png_fallback_is_masked(site: tuple[ServerProcess, str], browser: Any) -> None:
    server, _db = site
    page = start(browser, server, (1366, 768), "oval-png")
    page.goto(page.url.split("?")[0] + "?render=png")  # the session page without WebGL
    wait_ready(page, "instructions")
    page.get_by_role("button", name="Begin").click()
    wait_ready(page, "trial")
    assert page.evaluate("window.emogenStudy.display") == "png"
    # the PNG the server sent, as it is (not as the page scales it)
    src = page.get_attribute("#grid > .cell:nth-child(1) .slot img", "src")
    response = page.request.get(f"{server.url}{src}" if src.startswith("/") else src)
    assert response.ok and response.headers["content-type"] == "image/png"
    png = np.asarray(Image.open(io.BytesIO(response.body())).convert("RGB"), dtype=int)
    assert off_background(png[outside_oval(png.shape)]).max() <= 1
    assert (off_background(png[~outside_oval(png.shape, -0.4)]) > 10).mean() > 0.9
    # and on the screen: the page shows the masked PNG as the tile
    marks(page, "hidden")
    shown = tile(page.locator("#grid > .cell:nth-child(1) .slot"))
    assert off_background(shown[outside_oval(shown.shape)]).max() <= 2
    page.context.close()


def test_jspsych_plugin_shows_the_study_framing(
    browser: Any, tmp_path: Path, ict_dir: Path, viewer_bundle: Path
) -> None:
    """The plugin reads the framing from GET /api/study: its categorise face is oval too."""
    build_plugin()
    site = ExperimentSite(tmp_path / "site")
    study = {
        **OVAL_STUDY,
        "name": "oval-embedded",
        "emotions": ["happy", "sad"],
        "blocks": [{"task": "categorise", "random": 1, "labels": ["happy", "sad"]}],
    }
    srv, _url = serve(study, site, tmp_path, ict_dir)
    try:
        site.add("oval.html", one_trial_page(srv.url, [{"task": "categorise"}]))
        page = open_page(browser, f"{site.origin}/oval.html?PROLIFIC_PID=oval-js", (1366, 768))
        wait_stage(page, "categorise")
        assert page.evaluate(
            "document.querySelector('#categorise-slot canvas, .faces-canvas') !== null"
        )
        face = tile(page.locator("#categorise-slot"))
        page.screenshot(path=str(SCREENSHOTS / "oval-jspsych-categorise-1366x768.png"))
        assert off_background(face[outside_oval(face.shape)]).max() <= 2
        assert (off_background(face[~outside_oval(face.shape, -0.4)]) > 10).mean() > 0.9
        page.context.close()
    finally:
        srv.stop()
        site.close()
