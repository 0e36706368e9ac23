"""The participant page on phones, tablets and desktops (Debian's Chromium through Playwright).

At every viewport of the issue (360×640 … 2560×1440): the prompt is fully visible, Next is
reachable without horizontal scrolling, and faces are at least 40 % of the viewport's width or
five to a row (3D viewer and PNG fallback alike). Then the page's behaviour: a lost connection is
said at once and retried until the server answers, Back stays in the study, the personal link
is shown and copied, and the keyboard does what the instructions say.

Screenshots go to /tmp/emogen-device-screenshots; ``EMOGEN_UPDATE_SCREENSHOTS=1`` writes the
ones docs/study.md shows (docs/images/devices_<w>x<h>.png, and the rating and the pause between
trials at 390×844).
"""

from __future__ import annotations

import itertools
import os
import re
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from benchmarks.bench_study import ServerProcess, write_study_toml

from tests.web.test_study_browser import BROWSER_STUDY, browser, viewer_bundle, wait_for, wait_ready

pytestmark = [pytest.mark.browser, pytest.mark.slow]

REPO = Path(__file__).resolve().parents[2]
VIEWPORTS = [(360, 640), (390, 844), (768, 1024), (1366, 768), (2560, 1440)]
SCREENSHOTS = (
    REPO / "docs" / "images"
    if os.environ.get("EMOGEN_UPDATE_SCREENSHOTS") == "1"
    else Path("/tmp/emogen-device-screenshots")
)
_ = (browser, viewer_bundle)  # fixtures, requested by name
#: The rating question names the emotion asked for (as the example design's does).
RATING = {"question": "How well does this face show {EMOTION}?"}


@pytest.fixture(scope="module")
def site(
    tmp_path_factory: pytest.TempPathFactory, ict_dir: Path, ict_model, viewer_bundle: Path
) -> Iterator[ServerProcess]:  # type: ignore[no-untyped-def]
    """One server (SQLite) for the module; each test starts its own participant."""
    tmp = tmp_path_factory.mktemp("devices")
    config = write_study_toml({**BROWSER_STUDY, "rating": RATING}, tmp / "devices.toml")
    srv = ServerProcess(config, f"sqlite:///{tmp / 'study.sqlite'}", ict_dir, tmp / "server.log")
    yield srv.start()
    srv.stop()


def start(browser: Any, site: ServerProcess, size: tuple[int, int], pid: str, **ctx: Any) -> Any:
    """A new participant's page at the instructions (consent given)."""
    context = browser.new_context(viewport={"width": size[0], "height": size[1]}, **ctx)
    page = context.new_page()
    page.on("pageerror", lambda e: pytest.fail(f"page error: {e}"))
    page.goto(f"{site.url}/?PROLIFIC_PID={pid}")
    page.get_by_role("button", name="I agree").click()
    wait_ready(page, "instructions")
    return page


def no_horizontal_overflow(page: Any) -> None:
    width, inner = page.evaluate("[document.scrollingElement.scrollWidth, innerWidth]")
    assert width <= inner, f"the page is {width} px wide in a {inner} px viewport"


def inside_viewport(page: Any, selector: str) -> dict[str, float]:
    page.locator(selector).scroll_into_view_if_needed()
    box = page.locator(selector).bounding_box()
    w, h = page.viewport_size["width"], page.viewport_size["height"]
    assert box is not None, selector
    assert box["x"] >= 0 and box["y"] >= 0, (selector, box)
    assert box["x"] + box["width"] <= w + 0.5 and box["y"] + box["height"] <= h + 0.5, (
        selector,
        box,
        (w, h),
    )
    return box  # type: ignore[no-any-return]


def check_trial_layout(page: Any, width: int, height: int) -> None:
    page.evaluate("scrollTo(0, 0)")
    inside_viewport(page, "#prompt")
    cut = page.eval_on_selector(
        "#prompt",
        "e => [e.scrollWidth - e.clientWidth, e.scrollHeight - e.clientHeight, e.innerText]",
    )
    assert cut[0] <= 0 and cut[1] <= 1, f"prompt cut: {cut}"
    assert re.search(r"Make the face look (HAPPY|SAD)", cut[2]), cut[2]
    no_horizontal_overflow(page)
    boxes = page.eval_on_selector_all(
        "#grid > .cell",
        "cs => cs.map(c => { const r = c.getBoundingClientRect(); "
        "return [r.x, r.y, r.width, r.height]; })",
    )
    assert len(boxes) == 10
    columns = len({round(b[0]) for b in boxes})
    sizes = [b[2] for b in boxes]
    assert max(sizes) - min(sizes) < 1 and all(abs(b[2] - b[3]) < 1 for b in boxes)  # square
    if width < 700 and height > width:  # a phone upright: all ten faces seen at once, no scroll
        outside = [i + 1 for i, b in enumerate(boxes) if b[1] < 0 or b[1] + b[3] > height + 0.5]
        assert not outside, f"faces {outside} are below the fold at {width}x{height}"
        assert sizes[0] >= 90, (sizes[0], width, height)  # still large enough to judge
        actions = page.eval_on_selector(".actions", "e => e.getBoundingClientRect().top")
        assert all(b[1] + b[3] <= actions + 0.5 for b in boxes), "a face is under the action bar"
    else:
        assert sizes[0] >= 0.4 * width or columns == 5, (sizes[0], width, columns)
    assert all(b[0] >= 0 and b[0] + b[2] <= width + 0.5 for b in boxes)
    if page.evaluate("window.emogenStudy.display") == "webgl":  # the canvas covers the grid
        grid, canvas = (
            page.eval_on_selector(
                s,
                "e => { const r = e.getBoundingClientRect(); "
                "return [r.x, r.y, r.width, r.height]; }",
            )
            for s in ("#grid", "#grid > canvas")
        )
        assert all(abs(a - b) < 1 for a, b in zip(grid, canvas, strict=True)), (grid, canvas)
    else:
        imgs = page.eval_on_selector_all(
            "#grid .slot img", "is => is.map(i => [i.complete, i.getBoundingClientRect().width])"
        )
        assert len(imgs) == 10 and all(ok and abs(w - sizes[0]) < 12 for ok, w in imgs), imgs
    inside_viewport(page, "#next")
    # the marks are explained on the screen: the ★ on a face, ★ best, ✓ also acceptable
    inside_viewport(page, "#star-help")
    legend = page.inner_text("#star-help")
    assert "★ best" in legend and "✓ also acceptable" in legend and "★ on a face" in legend
    no_horizontal_overflow(page)


def choose_two(page: Any) -> None:
    page.click("#grid > .cell:nth-child(2) .face")
    page.click("#grid > .cell:nth-child(5) .face")
    assert page.is_enabled("#next")


@pytest.mark.parametrize(("width", "height"), VIEWPORTS, ids=[f"{w}x{h}" for w, h in VIEWPORTS])
def test_every_view_fits_the_screen(
    browser: Any, site: ServerProcess, width: int, height: int
) -> None:
    page = start(browser, site, (width, height), f"dev-{width}x{height}")
    no_horizontal_overflow(page)
    inside_viewport(page, "#resume-link")
    inside_viewport(page, "#begin")
    page.click("#begin")
    wait_ready(page, "trial")
    assert page.evaluate("window.emogenStudy.display") == "webgl"
    assert page.evaluate("document.body.dataset.loaded").endswith("bytes")
    check_trial_layout(page, width, height)
    choose_two(page)
    SCREENSHOTS.mkdir(parents=True, exist_ok=True)
    page.evaluate("scrollTo(0, 0)")
    page.screenshot(path=str(SCREENSHOTS / f"devices_{width}x{height}.png"))
    # landscape (turned phone or tablet, a portrait monitor): still fits
    page.set_viewport_size({"width": height, "height": width})
    page.wait_for_timeout(100)
    check_trial_layout(page, height, width)
    page.set_viewport_size({"width": width, "height": height})
    page.click("#next")
    wait_ready(page, "trial")
    choose_two(page)
    page.click("#next")
    wait_ready(page, "rating")
    no_horizontal_overflow(page)
    inside_viewport(page, "#prompt")  # the prompt stays above the rating ("Make the face …")
    assert page.inner_text("#prompt").startswith("Make the face look")
    inside_viewport(page, "#rating-question")
    asked = page.inner_text("#prompt").removeprefix("Make the face look ")
    assert page.inner_text("#rating-question") == f"How well does this face show {asked}?"
    assert asked in ("HAPPY", "SAD")
    page.get_by_label("4", exact=True).check()
    inside_viewport(page, "#rate")
    if (width, height) == (390, 844):
        page.evaluate("scrollTo(0, 0)")
        page.screenshot(path=str(SCREENSHOTS / "devices_rating_390x844.png"))
        page.click("#rate")
        wait_for(page, "window.emogenStudy.stage === 'transition'", timeout=10_000)
        page.screenshot(path=str(SCREENSHOTS / "devices_transition_390x844.png"))
    page.context.close()


@pytest.mark.parametrize(("width", "height"), [(360, 640), (1366, 768)], ids=["phone", "laptop"])
def test_the_png_fallback_follows_the_layout(
    browser: Any, site: ServerProcess, width: int, height: int
) -> None:
    page = start(browser, site, (width, height), f"png-{width}")
    page.goto(page.url.split("?")[0] + "?render=png")
    wait_ready(page, "instructions")
    page.click("#begin")
    wait_ready(page, "trial")
    assert page.evaluate("window.emogenStudy.display") == "png"
    assert page.evaluate("document.body.dataset.loaded") == "10/10 faces"
    check_trial_layout(page, width, height)
    page.context.close()


def test_a_lost_connection_is_said_at_once_and_retried_until_the_server_answers(
    browser: Any, site: ServerProcess
) -> None:
    page = start(browser, site, (390, 844), "dev-offline")
    page.click("#begin")
    wait_ready(page, "trial")
    before = page.eval_on_selector("#grid > .cell", "c => c.dataset.face")
    sent: list[str] = []
    # after Begin, the one step route carries only the selection
    page.on("request", lambda r: sent.append(r.url) if r.url.endswith("/step") else None)
    page.route("**/step", lambda route: route.abort("internetdisconnected"))
    choose_two(page)
    page.click("#next")
    wait_for(
        page,
        "document.querySelector('#message').innerText.includes('Connection lost')",
        timeout=3000,
    )
    assert re.search(r"Connection lost — retrying in \d+ s…", page.inner_text("#message"))
    assert page.is_disabled("#next") and page.inner_text("#next") == "Saving…"
    assert "Saving" in page.inner_text("#selection-status")
    page.click("#next", force=True)  # a second press while saving sends nothing more
    # it keeps retrying, longer and longer (1 s, 2 s, 4 s …), and still says so
    page.wait_for_timeout(3500)
    assert len(sent) >= 3
    assert "retrying" in page.inner_text("#message")
    page.unroute("**/step")
    wait_for(
        page, f"document.querySelector('#grid > .cell').dataset.face !== '{before}'", timeout=15_000
    )
    wait_ready(page, "trial")
    assert "Round 2 of 2" in page.inner_text("#progress")
    assert "Connection lost" not in page.inner_text("#message")
    page.context.close()


def test_a_crowded_start_waits_as_the_server_asks_and_gets_in(
    browser: Any, site: ServerProcess
) -> None:
    """A room starting at once behind one address: the server answers 429 with Retry-After (here
    twice, then lets the request through); the page says so, waits that long and gets in."""
    context = browser.new_context(viewport={"width": 1366, "height": 768})
    page = context.new_page()
    page.on("pageerror", lambda e: pytest.fail(f"page error: {e}"))
    tries: list[float] = []

    def limit(route: Any) -> None:
        tries.append(time.monotonic())
        if len(tries) <= 2:
            route.fulfill(
                status=429,
                headers={"Retry-After": "2"},
                content_type="application/json",
                body='{"detail": "too many new sessions from this address"}',
            )
        else:
            route.continue_()

    page.route("**/api/sessions", limit)
    page.goto(f"{site.url}/?PROLIFIC_PID=dev-crowded")
    page.get_by_role("button", name="I agree").click()
    wait_for(page, "document.querySelector('#message').innerText.includes('Many people')", 3000)
    said = page.inner_text("#message")
    assert re.fullmatch(r"Many people are starting at once — you will be in in [2-4] s\.", said)
    assert page.is_disabled("#agree")
    wait_ready(page, "instructions")
    assert len(tries) == 3
    assert all(b - a >= 1.95 for a, b in itertools.pairwise(tries)), tries
    context.close()


def test_back_stays_in_the_study(browser: Any, site: ServerProcess) -> None:
    page = start(browser, site, (1366, 768), "dev-back")
    url = page.url
    page.click("#begin")
    wait_ready(page, "trial")
    choose_two(page)
    page.click("#next")
    wait_ready(page, "trial")
    for _ in range(2):
        page.go_back()
        page.wait_for_timeout(200)
        assert page.url == url
        assert page.evaluate("window.emogenStudy.stage") == "trial"
        assert "Back does not undo" in page.inner_text("#message")
    assert "Round 2 of 2" in page.inner_text("#progress")
    page.context.close()


def test_the_personal_link_is_shown_copied_and_works_elsewhere(
    browser: Any, site: ServerProcess
) -> None:
    page = start(browser, site, (390, 844), "dev-link")
    page.context.grant_permissions(["clipboard-read", "clipboard-write"], origin=site.url)
    token = page.url.split("/s/")[1].split("?")[0]
    link = page.input_value("#resume-link")
    assert link == f"{site.url}/s/{token}"
    assert "another device" in page.inner_text("#resume")
    page.click("#copy-link")
    wait_for(page, "document.querySelector('#copy-status').innerText.includes('Copied')")
    assert page.evaluate("navigator.clipboard.readText()") == link
    page.click("#begin")
    wait_ready(page, "trial")
    faces = page.eval_on_selector_all("#grid > .cell", "cs => cs.map(c => c.dataset.face)")
    # another browser (a fresh context: no cookies, no storage) continues the same session
    other = browser.new_context(viewport={"width": 1366, "height": 768}).new_page()
    other.goto(link)
    wait_ready(other, "trial")
    assert other.eval_on_selector_all("#grid > .cell", "cs => cs.map(c => c.dataset.face)") == faces
    other.context.close()
    page.context.close()


def test_the_keyboard_does_what_the_instructions_say(browser: Any, site: ServerProcess) -> None:
    page = start(browser, site, (1366, 768), "dev-keys")
    said = page.inner_text("#view-instructions")
    assert "Tab or the arrow keys move between faces" in said
    assert "Enter or Space selects" in said and "B makes a face the best" in said
    page.click("#begin")
    wait_ready(page, "trial")

    def focused() -> int:
        return int(page.evaluate("document.activeElement.closest('.cell').dataset.pos"))

    page.focus("#grid > .cell:nth-child(1) .face")
    page.keyboard.press("Tab")
    assert focused() == 1  # Tab: the next face
    page.keyboard.press("Tab")
    page.keyboard.press("Shift+Tab")
    assert focused() == 1
    page.keyboard.press("ArrowRight")
    assert focused() == 2
    page.keyboard.press("ArrowDown")
    assert focused() == 7  # a row is five faces here
    page.keyboard.press("Enter")  # selects: the first is the best
    assert page.get_attribute("#grid > .cell:nth-child(8)", "data-role") == "best"
    page.keyboard.press("ArrowUp")
    page.keyboard.press("Space")  # selects: also acceptable
    assert page.get_attribute("#grid > .cell:nth-child(3)", "data-role") == "ok"
    page.keyboard.press("b")  # the focused face becomes the best
    assert page.get_attribute("#grid > .cell:nth-child(3)", "data-role") == "best"
    assert page.get_attribute("#grid > .cell:nth-child(8)", "data-role") == "ok"
    page.keyboard.press("Space")  # and Space removes it again
    assert page.get_attribute("#grid > .cell:nth-child(3)", "data-role") == "none"
    page.keyboard.press("End")
    page.keyboard.press("Tab")  # after the last face: the buttons
    assert page.evaluate("document.activeElement.id") in ("restart", "next")
    page.context.close()


@pytest.mark.parametrize(
    ("size", "touch", "verb"),
    [((1366, 768), False, "Click"), ((390, 844), True, "Tap")],
    ids=["mouse", "touch"],
)
def test_the_first_hint_says_click_with_a_mouse_and_tap_on_a_touch_screen(
    browser: Any, site: ServerProcess, size: tuple[int, int], touch: bool, verb: str
) -> None:
    page = start(browser, site, size, f"hint-{verb}", has_touch=touch, is_mobile=touch)
    page.click("#begin")
    wait_ready(page, "trial")
    hint = page.inner_text("#selection-status")
    assert hint == f"{verb} the face most like the emotion: it becomes ★ best.", hint
    page.context.close()
