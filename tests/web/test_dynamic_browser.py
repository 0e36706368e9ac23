"""A participant evolves a face that moves (an evolve block with ``dynamic = {}``) in Debian's
Chromium (Playwright), the 3D viewer on: ``emogen serve`` serves the block; the ten tiles play
their clips (their pixels change over time) in sync, one tile is stepped through with the
slider while the others play, "Play all again" restarts them together; the participant
chooses through every generation and rates, and the records are as a static block's (every
face shown, every selection) plus the faces' curves, and the session replays.
"""

from __future__ import annotations

import io
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from benchmarks.bench_study import ServerProcess, write_study_toml
from PIL import Image

from emogen.study.export import export_tables
from emogen.study.replay import replay_session
from emogen.study.storage import Store
from tests.web.test_study_browser import CSP_PROBE, browser, shown_faces, viewer_bundle, wait_ready
from tests.web.viewer_site import screenshot_folder

pytestmark = [pytest.mark.browser, pytest.mark.slow]
_ = (browser, viewer_bundle)  # fixtures, requested by name

DYNAMIC_STUDY: dict[str, Any] = {
    "name": "moving",
    "emotions": ["happy"],
    "order": "fixed",
    "seed": 11,
    "ga": {"generations": 1, "min_selections": 1, "max_selections": 3},
    "completion": {"code": "MOVING-OK"},
    "blocks": [{"task": "evolve", "dynamic": {}}],
}


@pytest.fixture(scope="module")
def site(
    tmp_path_factory: pytest.TempPathFactory, ict_dir: Path, viewer_bundle: Path
) -> Iterator[tuple[ServerProcess, str]]:
    tmp = tmp_path_factory.mktemp("dynamic")
    db = f"sqlite:///{tmp / 'study.sqlite'}"
    config = write_study_toml(DYNAMIC_STUDY, tmp / "moving.toml")
    srv = ServerProcess(config, db, ict_dir, tmp / "server.log")
    yield srv.start(), db
    srv.stop()


def tiles(page: Any) -> list[np.ndarray]:
    """The ten tiles' pixels at one instant (one screenshot of the page, cut by the tiles'
    boxes: an element screenshot waits for a still frame, which playing tiles never give)."""
    shot = np.asarray(Image.open(io.BytesIO(page.screenshot())).convert("RGB"), dtype=int)
    boxes = page.eval_on_selector_all(
        "#grid > .cell .slot",
        "ss => ss.map((s) => { const r = s.getBoundingClientRect();"
        " return [r.left, r.top, r.right, r.bottom].map(Math.round); })",
    )
    return [shot[top + 4 : bottom - 4, left + 4 : right - 4] for left, top, right, bottom in boxes]


def tiles_moving(page: Any, want: int = 8, seconds: float = 30.0) -> list[float]:
    """How far each tile's pixels moved from the first look (mean absolute change), sampled
    every 250 ms over a whole loop and more (2.5 s: a tile whose clip ends early rests a while),
    and on until ``want`` tiles have moved or ``seconds`` have passed: software GL on a loaded
    machine can take over a second a frame, so a fixed window would test the machine's load."""
    series = [tiles(page)]
    moved = [0.0] * len(series[0])
    for sample in range(int(seconds / 0.25)):
        page.wait_for_timeout(250)
        series.append(tiles(page))
        moved = [max(np.abs(s[k] - series[0][k]).mean() for s in series[1:]) for k in range(10)]
        if sample >= 10 and sum(m > 0.05 for m in moved) >= want:
            break
    return moved


def clip_times(page: Any) -> list[float]:
    times: list[float | None] = page.evaluate("window.emogenStudy.clipTimes()")
    return [t for t in times if t is not None]


def replay_now(page: Any) -> list[float]:
    """Press "Play all again" and read the clip times in the same task of the page."""
    times: list[float | None] = page.evaluate(
        "() => { document.getElementById('replay').click();"
        " return window.emogenStudy.clipTimes(); }"
    )
    return [t for t in times if t is not None]


def scrub(page: Any, t: float) -> None:
    page.evaluate(
        "t => { const s = document.getElementById('scrub'); s.value = String(t);"
        " s.dispatchEvent(new Event('input')); }",
        t,
    )


def test_a_participant_evolves_a_moving_face(
    site: tuple[ServerProcess, str], browser: Any, ict_model: Any
) -> None:
    server, db_url = site
    context = browser.new_context(viewport={"width": 1366, "height": 768})
    context.add_init_script(CSP_PROBE)
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(f"{server.url}/?PROLIFIC_PID=mover-1")
    page.get_by_role("button", name="I agree").click()
    wait_ready(page, "instructions")
    page.get_by_role("button", name="Begin").click()
    wait_ready(page, "trial")
    assert page.evaluate("window.emogenStudy.display") == "webgl"
    assert page.is_visible("#motion") and page.is_visible("#replay")

    # ---- the ten tiles play: each tile's pixels change over the 2 s loop ----
    moved = tiles_moving(page)
    assert sum(m > 0.05 for m in moved) >= 8, moved  # a blank face (no gene on) stands still
    # …in sync: every tile at the same clip time
    times = clip_times(page)
    assert len(times) == 10 and max(times) - min(times) < 0.02, times  # asked one by one
    folder = screenshot_folder("dynamic")
    folder.mkdir(exist_ok=True, parents=True)
    page.screenshot(path=str(folder / "dynamic-trial-1366x768.png"))

    # ---- one tile stepped through: face 3 held where the slider is, the others play on ----
    page.focus("#grid > .cell:nth-child(1) .face")
    page.keyboard.press("ArrowRight")
    page.keyboard.press("ArrowRight")  # face 3
    assert page.inner_text("#scrub-face") == "3"
    scrub(page, 0.9)
    # both reads in one task of the page, 0.8 s apart by its own clock: longer than the hold (when
    # a clip's time stands still) and shorter than the loop (two reads a whole loop apart, as a
    # loaded machine's delays between separate calls made them once, show the same times)
    first, later = page.evaluate(
        "() => { const times = () => window.emogenStudy.clipTimes().filter((t) => t !== null);"
        " const first = times(); const t0 = performance.now();"
        " while (performance.now() - t0 < 800) {} return [first, times()]; }"
    )
    assert first[2] == later[2] == 0.9
    assert any(
        abs(a - b) > 0.05 for k, (a, b) in enumerate(zip(first, later, strict=True)) if k != 2
    )
    held = tiles(page)[2]
    scrub(page, 0.3)
    page.wait_for_timeout(200)
    assert np.abs(tiles(page)[2] - held).mean() > 0.05  # another time, another frame

    # ---- "Play all again": every tile from the clip's start, face 3 playing along again ----
    # pressed and read in one task of the page: every tile at the clip's start
    times = replay_now(page)
    assert len(times) == 10 and max(times) < 0.05, times
    page.wait_for_timeout(300)
    times = clip_times(page)
    assert max(times) - min(times) < 0.02, times  # face 3 plays along again
    assert page.input_value("#scrub") == "0"

    # ---- choosing works as for still faces, through every generation, then the rating ----
    shown, chosen = [], []
    for generation in (0, 1):
        ids = shown_faces(page)
        shown.append(ids)
        page.click("#grid > .cell:nth-child(4) .face")
        page.click("#grid > .cell:nth-child(2) .face")
        chosen.append((ids[3], [ids[1]]))
        page.click("#next")
        wait_ready(page, "rating" if generation == 1 else "trial")
        if generation == 0:
            assert len(clip_times(page)) == 10  # the new faces play too
    # the rated face moves too
    assert page.evaluate("window.emogenStudy.clipTimes().filter((t) => t !== null).length") == 1
    page.get_by_label("5", exact=True).check()
    page.click("#rate")
    wait_ready(page, "done")
    assert page.inner_text("#done-code") == "MOVING-OK"
    assert errors == []
    assert page.evaluate("window.__cspViolations") == []
    context.close()

    # ---- the records: as a static block's, and the curves of every face shown ----
    store = Store(db_url)
    tables = export_tables(store)
    faces = tables["faces"]
    for generation, ids in enumerate(shown):
        rows = faces[faces.generation == generation].sort_values("position")
        assert rows.face_id.tolist() == ids
    sel = tables["selections"]
    for generation, (elite, others) in enumerate(chosen):
        rows = sel[sel.generation == generation].sort_values("rank")
        assert rows.face_id.tolist() == [elite, *others]
        assert (rows.load_ms > 0).all() and (rows.client_response_ms > 0).all()
        assert rows.fallback.tolist() == [False] * len(rows)  # the 3D viewer showed them
    assert tables["evolve_ratings"].value.tolist() == [5]
    assert tables["evolve_ratings"].fallback.tolist() == [False]
    first = faces[faces.generation == 0].sort_values("position")
    genes = first[[c for c in first.columns if c.startswith("g_")]].to_numpy()
    assert [m > 0.05 for m in moved] == (genes.max(axis=1) > 0).tolist(), moved
    curves = tables["face_curves"]
    g_columns = [c for c in faces.columns if c.startswith("g_")]
    moving = faces[faces[g_columns].to_numpy().max(axis=1) > 0]  # a blank face has no curve
    assert set(zip(curves.generation, curves.face_id, strict=True)) == set(
        zip(moving.generation, moving.face_id, strict=True)
    )
    assert replay_session(store, 1, ict_model.rig, ict_model.model_hash, model=ict_model).ok
    store.dispose()


def test_without_webgl_the_tiles_flip_through_strips_of_frames(
    site: tuple[ServerProcess, str], browser: Any
) -> None:
    """``?render=png`` (as a browser without WebGL 2): each moving face is the server's strip of
    11 frames, shown a frame at a time, in sync; the slider holds one; the page says "png"."""
    server, db_url = site
    context = browser.new_context(viewport={"width": 1366, "height": 768})
    context.add_init_script(CSP_PROBE)
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(f"{server.url}/?PROLIFIC_PID=mover-png")
    page.get_by_role("button", name="I agree").click()
    wait_ready(page, "instructions")
    page.goto(page.url.split("?")[0] + "?render=png")  # the session page without WebGL
    wait_ready(page, "instructions")
    page.get_by_role("button", name="Begin").click()
    wait_ready(page, "trial")
    assert page.evaluate("window.emogenStudy.display") == "png"
    sizes = page.eval_on_selector_all(
        "#grid > .cell .slot img", "is => is.map((i) => [i.naturalWidth, i.naturalHeight])"
    )
    assert len(sizes) == 10 and all(w == 11 * h for w, h in sizes), sizes
    assert page.eval_on_selector_all("#grid > .cell .slot.strip", "ss => ss.length") == 10
    moved = tiles_moving(page)
    assert sum(m > 0.05 for m in moved) >= 8, moved
    times = clip_times(page)
    assert len(times) == 10 and max(times) - min(times) < 0.02, times  # asked one by one
    page.focus("#grid > .cell:nth-child(1) .face")
    page.keyboard.press("ArrowRight")  # face 2
    scrub(page, 0.5)
    page.wait_for_timeout(300)
    assert clip_times(page)[1] == 0.5
    times = replay_now(page)
    assert len(times) == 10 and max(times) < 0.05, times
    page.click("#grid > .cell:nth-child(2) .face")
    page.click("#next")
    wait_ready(page, "trial")
    assert page.evaluate("window.emogenStudy.display") == "png"
    assert errors == [] and page.evaluate("window.__cspViolations") == []
    context.close()
    store = Store(db_url)  # the selection says the strips showed its faces
    sel = export_tables(store)["selections"]
    assert sel[sel.participant_id == "mover-png"].fallback.tolist() == [True]
    store.dispose()
