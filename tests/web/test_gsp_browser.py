"""A GSP block in Debian's Chromium (Playwright): one participant on a desktop (3D viewer,
keyboard), one on a phone (3D viewer, touch), one without WebGL (the server's images: the strip
of nine pictures). The face morphs live as the slider moves (the drawn pixels change with every
step, and match the face the server sent for that position); the slider starts where the
server drew it; what the page sent is what the export holds, and the sessions replay.

Screenshots go to /tmp/emogen-gsp-screenshots; ``EMOGEN_UPDATE_SCREENSHOTS=1`` writes the ones
docs/study.md shows (docs/images/gsp_<w>x<h>.jpg, gsp_png_1366x768.jpg). The slider's frame
rate is measured by ``python -m benchmarks.bench_gsp_slider`` (a benchmark, not a test)."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from benchmarks.bench_study import ServerProcess, write_study_toml

from emogen.study.export import export_tables
from emogen.study.replay import replay_session
from emogen.study.storage import Store
from tests.web.test_devices import inside_viewport, no_horizontal_overflow
from tests.web.test_study_browser import CSP_PROBE, browser, viewer_bundle, wait_ready
from tests.web.viewer_site import screenshot_folder

pytestmark = [pytest.mark.browser, pytest.mark.slow]
_ = (browser, viewer_bundle)  # fixtures, requested by name

SCREENSHOTS = screenshot_folder("gsp")
GSP_STUDY: dict[str, Any] = {
    "name": "gsp-browser",
    "emotions": ["happy", "sad"],
    "identities": ["female-medium"],
    "seed": 9,
    "completion": {"code": "GSP-OK"},
    "blocks": [
        {
            "task": "gsp",
            "chains": 2,
            "iterations": 2,
            "steps": 21,
            "prompt": "Move the slider until the face looks as {emotion} as possible",
        }
    ],
}
TRIALS = 2 * 2


@pytest.fixture(scope="module")
def site(
    tmp_path_factory: pytest.TempPathFactory, ict_dir: Path, ict_model, viewer_bundle: Path
) -> Iterator[tuple[ServerProcess, str]]:  # type: ignore[no-untyped-def]
    tmp = tmp_path_factory.mktemp("gsp")
    config = write_study_toml(GSP_STUDY, tmp / "gsp.toml")
    url = f"sqlite:///{tmp / 'study.sqlite'}"
    srv = ServerProcess(config, url, ict_dir, tmp / "server.log").start()
    yield srv, url
    srv.stop()


def start(browser: Any, srv: ServerProcess, size: tuple[int, int], pid: str, **ctx: Any) -> Any:
    context = browser.new_context(viewport={"width": size[0], "height": size[1]}, **ctx)
    context.add_init_script(CSP_PROBE)
    page = context.new_page()
    page.on("pageerror", lambda e: pytest.fail(f"page error: {e}"))
    page.goto(f"{srv.url}/?PROLIFIC_PID={pid}")
    page.get_by_role("button", name="I agree").click()
    wait_ready(page, "instructions")
    page.get_by_role("button", name="Begin").click()
    return page


def state_of(page: Any, srv: ServerProcess) -> dict[str, Any]:
    import httpx

    token = page.url.split("/s/")[1].split("?")[0]
    return httpx.get(f"{srv.url}/api/s/{token}/state", timeout=30).json()  # type: ignore[no-any-return]


# The GSP slot's kept frames (viewer/kept.js): {shown, kept, of, complete}.
KEPT = "() => window.emogenStudy.keptFrames().find(Boolean)"


def face_pixels(page: Any) -> bytes:
    return page.locator("#gsp-slot").screenshot()  # type: ignore[no-any-return]


def recorded(url: str, pid: str, model: Any) -> Any:
    store = Store(url)
    try:
        tables = export_tables(store)
        sessions = tables["sessions"]
        sid = int(sessions.loc[sessions.participant_id == pid, "session_id"].iloc[0])
        rows = tables["gsp_iterations"].query("session_id == @sid").sort_values("trial")
        report = replay_session(store, sid, model.rig, model.model_hash, model=model)
        return rows, report
    finally:
        store.dispose()


@pytest.mark.parametrize(
    ("size", "keyboard"), [((1366, 768), True), ((390, 844), False)], ids=["desktop", "phone"]
)
def test_a_participant_moves_the_slider_and_the_face_follows(
    browser: Any,
    site: tuple[ServerProcess, str],
    ict_model: Any,
    size: tuple[int, int],
    keyboard: bool,
) -> None:
    srv, url = site
    pid = f"gsp-{size[0]}"
    page = start(browser, srv, size, pid, has_touch=not keyboard, is_mobile=not keyboard)
    sent = []
    for k in range(TRIALS):
        wait_ready(page, "gsp")
        state = state_of(page, srv)
        view = state["view"]
        assert view["task"] == "gsp" and not view["waiting"] and "dimension" not in view
        assert page.inner_text("#prompt") == (
            f"Move the slider until the face looks as {view['emotion']} as possible"
        )
        assert page.evaluate("window.emogenStudy.display") == "webgl"
        start_at = view["slider"]["start"]
        assert page.input_value("#gsp-slider") == str(start_at)  # where the server drew it
        before = face_pixels(page)
        if keyboard:
            page.focus("#gsp-slider")
            key = "ArrowLeft" if start_at > 10 else "ArrowRight"
            for _ in range(3):
                page.keyboard.press(key)
            want = start_at - 3 if key == "ArrowLeft" else start_at + 3
        else:
            box = page.locator("#gsp-slider").bounding_box()
            share = 0.15 if start_at > 10 else 0.85
            page.touchscreen.tap(box["x"] + share * box["width"], box["y"] + box["height"] / 2)
            want = int(page.input_value("#gsp-slider"))
            assert abs(want - share * 20) <= 2 and want != start_at
        assert int(page.input_value("#gsp-slider")) == want
        after = face_pixels(page)
        assert after != before  # the face followed the slider, live
        # the face shown is the one of the slider's position (the viewer's kept frames hold
        # the view's faces, position by position: tests/web/test_kept_frames.py)
        kept = page.evaluate(KEPT)
        assert kept["shown"] == want and kept["of"] == view["slider"]["steps"]
        if k == 0:  # every frame kept: away and back, the same face, from its kept frame
            page.wait_for_function(f"() => ({KEPT})().complete", timeout=120_000, polling=100)
            page.evaluate(
                "v => { const s = document.getElementById('gsp-slider'); s.value = v;"
                " s.dispatchEvent(new Event('input', { bubbles: true })); }",
                str(start_at),
            )
            assert face_pixels(page) == before
            page.evaluate(
                "v => { const s = document.getElementById('gsp-slider'); s.value = v;"
                " s.dispatchEvent(new Event('input', { bubbles: true })); }",
                str(want),
            )
            assert face_pixels(page) == after and page.evaluate(KEPT)["shown"] == want
        if k == 0:
            page.evaluate("scrollTo(0, 0)")
            no_horizontal_overflow(page)
            face = inside_viewport(page, "#gsp-face")
            assert face["width"] >= min(0.55 * min(size), 300), face  # large
            inside_viewport(page, "#gsp-slider")
            inside_viewport(page, "#gsp-next")
            SCREENSHOTS.mkdir(parents=True, exist_ok=True)
            page.screenshot(path=str(SCREENSHOTS / f"gsp_{size[0]}x{size[1]}.jpg"), quality=80)
        sent.append({"trial": state["progress"]["trial"], "position": want, "start": start_at})
        if keyboard:
            page.keyboard.press("Enter")
        else:
            page.tap("#gsp-next")
    wait_ready(page, "done")
    assert page.inner_text("#done-code") == "GSP-OK"
    assert page.evaluate("window.__cspViolations") == []
    page.context.close()
    rows, report = recorded(url, pid, ict_model)
    assert rows["trial"].tolist() == [s["trial"] for s in sent]
    assert rows["position"].tolist() == [s["position"] for s in sent]
    assert rows["slider_start"].tolist() == [s["start"] for s in sent]
    assert not rows["fallback"].any() and (rows["client_response_ms"] > 0).all()
    assert report.ok and report.stimuli == TRIALS, report.mismatches


def test_without_webgl_a_strip_of_nine_pictures_stands_in(
    browser: Any, site: tuple[ServerProcess, str], ict_model: Any
) -> None:
    srv, url = site
    pid = "gsp-png"
    page = start(browser, srv, (1366, 768), pid)
    wait_ready(page, "gsp")
    page.goto(page.url.split("?")[0] + "?render=png")  # the session page without WebGL
    chosen = []
    for k in range(TRIALS):
        wait_ready(page, "gsp")
        view = state_of(page, srv)["view"]
        assert page.evaluate("window.emogenStudy.display") == "png"
        assert page.is_hidden("#gsp-slider") and page.is_hidden("#gsp-face")
        # the block's prompt speaks of a slider: the heading asks for a picture instead
        heading = f"Choose the picture where the face looks most {view['emotion'].upper()}"
        assert page.inner_text("#prompt") == heading
        assert page.inner_text("#gsp-status") == "Choose the picture that fits the word best."
        pictures = page.locator("#gsp-strip button")
        assert pictures.count() == 9
        loaded = page.eval_on_selector_all(
            "#gsp-strip img", "is => is.map(i => i.complete && i.naturalWidth > 0)"
        )
        assert loaded == [True] * 9
        assert page.is_disabled("#gsp-next")  # nothing chosen yet
        pictures.nth(6).click()
        assert pictures.nth(6).get_attribute("aria-pressed") == "true"
        if k == 0:
            # the nine pictures and "Next" fit a 768-pixel-high window without scrolling
            page.evaluate("scrollTo(0, 0)")
            bottom = page.evaluate(
                "document.getElementById('gsp-next').getBoundingClientRect().bottom"
            )
            assert bottom <= 768, bottom
            SCREENSHOTS.mkdir(parents=True, exist_ok=True)
            page.screenshot(path=str(SCREENSHOTS / "gsp_png_1366x768.jpg"), quality=80)
        chosen.append(view["strip"][6])
        page.click("#gsp-next")
    wait_ready(page, "done")
    page.context.close()
    rows, report = recorded(url, pid, ict_model)
    assert rows["position"].tolist() == chosen and rows["fallback"].all()
    assert report.ok and report.stimuli == TRIALS, report.mismatches
