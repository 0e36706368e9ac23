# ruff: noqa: F811  (pytest fixtures imported by name, then requested by name)
"""A participant completes a two-trial study in Debian's Chromium (Playwright), 3D viewer on.

Consent → instructions → trial 1 (keyboard only, a reload in the middle) → rating → trial 2
(mouse, one "Start again") → rating → completion code. The export then holds every generation
the page showed and every selection it made; nothing moved on the page while faces loaded.
"""

from __future__ import annotations

import shutil
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from benchmarks.bench_study import ServerProcess, write_study_toml

from emogen.study.export import export_tables
from emogen.study.replay import replay_session
from emogen.study.storage import Store
from tests.study_fixtures import db_url, pg_cluster  # noqa: F401
from tests.web.viewer_site import CHROMIUM, CHROMIUM_ARGS

pytestmark = [pytest.mark.browser, pytest.mark.slow]

REPO = Path(__file__).resolve().parents[2]
WEB = REPO / "src" / "emogen" / "web"
BUNDLE = WEB / "static" / "build" / "study-viewer.js"
BROWSER_STUDY: dict[str, Any] = {
    "name": "browser",
    "emotions": ["happy", "sad"],
    "order": "fixed",
    "seed": 99,
    "ga": {"generations": 1, "min_selections": 2, "max_selections": 3},
    "completion": {"code": "BROWSER-OK"},
}
SCREENSHOTS = Path("/tmp/emogen-study-screenshots")

# Cumulative layout shift, as Chromium reports it (shifts right after input excluded).
LAYOUT_SHIFT_PROBE = """
window.__shift = 0;
new PerformanceObserver((list) => {
  for (const e of list.getEntries()) if (!e.hadRecentInput) window.__shift += e.value;
}).observe({ type: "layout-shift", buffered: true });
"""


def _bundle_stale() -> bool:
    if not BUNDLE.is_file():
        return True
    sources = [WEB / "viewer_entry.js", WEB / "build.mjs", *(WEB / "viewer").glob("*")]
    return max(p.stat().st_mtime for p in sources if p.is_file()) > BUNDLE.stat().st_mtime


@pytest.fixture(scope="module")
def viewer_bundle() -> Path:
    """The 3D viewer bundle for the study pages (built here when missing or stale)."""
    if _bundle_stale():
        node = shutil.which("node")
        if node is None or not (REPO / "node_modules" / "three").is_dir():
            pytest.fail("the study viewer needs Node.js and `npm ci` (three, esbuild)")
        proc = subprocess.run(
            [node, str(WEB / "build.mjs")], cwd=REPO, capture_output=True, text=True
        )
        if proc.returncode != 0:
            pytest.fail(f"building the study viewer failed:\n{proc.stdout}\n{proc.stderr}")
    return BUNDLE


@pytest.fixture(scope="module")
def browser(playwright_api: Any) -> Iterator[Any]:
    if not Path(CHROMIUM).exists():
        pytest.fail(f"browser tests need Debian's Chromium at {CHROMIUM}: apt-get install chromium")
    b = playwright_api.chromium.launch(executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS)
    yield b
    b.close()


@pytest.fixture
def server(
    db_url: str, tmp_path: Path, ict_dir: Path, ict_model, viewer_bundle: Path
) -> Iterator[ServerProcess]:
    config = write_study_toml(BROWSER_STUDY, tmp_path / "browser.toml")
    srv = ServerProcess(config, db_url, ict_dir, tmp_path / "server.log").start()
    yield srv
    srv.stop()


#: Records the page's Content-Security-Policy violations (none allowed: the pages run under
#: the server's policy, no inline script or style, no eval).
CSP_PROBE = """
window.__cspViolations = [];
document.addEventListener("securitypolicyviolation", (e) => {
  window.__cspViolations.push(`${e.violatedDirective} ${e.blockedURI}`);
});
"""


def wait_for(page: Any, expression: str, timeout: float = 30_000) -> None:
    """``page.wait_for_function`` without eval in the page (its string predicates are eval'd,
    which the Content-Security-Policy forbids): poll through the devtools protocol instead."""
    from playwright.sync_api import Error

    deadline = time.monotonic() + timeout / 1000
    while True:
        try:
            if page.evaluate(f"() => Boolean({expression})"):
                return
        except Error as exc:  # the page navigated while asked: ask the new page
            if "context was destroyed" not in str(exc) and "navigat" not in str(exc):
                raise
        if time.monotonic() > deadline:
            raise TimeoutError(f"waited {timeout} ms for {expression}")
        page.wait_for_timeout(50)


def wait_ready(page: Any, stage: str) -> None:
    wait_for(
        page,
        f"window.emogenStudy && window.emogenStudy.ready && window.emogenStudy.stage === '{stage}'",
        timeout=60_000,
    )


def shown_faces(page: Any) -> list[int]:
    return page.eval_on_selector_all("#grid > .cell", "cs => cs.map(c => Number(c.dataset.face))")


def test_participant_completes_two_trials(
    server: ServerProcess, browser: Any, db_url: str, ict_model, ict_dir: Path, tmp_path: Path
) -> None:  # type: ignore[no-untyped-def]
    context = browser.new_context(viewport={"width": 1366, "height": 768})
    context.add_init_script(LAYOUT_SHIFT_PROBE)
    context.add_init_script(CSP_PROBE)
    page = context.new_page()
    page.on("dialog", lambda d: d.accept())  # "Start again?" confirmation
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    shown: list[tuple[int, int, int, list[int]]] = []  # (trial, attempt, generation, face ids)
    chosen: list[tuple[int, int, int, int, list[int]]] = []  # (+ elite, others)

    page.goto(f"{server.url}/?PROLIFIC_PID=browser-1")
    page.get_by_role("button", name="I agree").click()
    wait_ready(page, "instructions")
    page.get_by_role("button", name="Begin").click()
    wait_ready(page, "trial")
    assert page.evaluate("window.emogenStudy.display") == "webgl"
    assert "Make the face look HAPPY" in page.inner_text("#prompt")
    assert "Trial 1 of 2" in page.inner_text("#progress")
    assert "Round 1 of 2" in page.inner_text("#progress")  # ga.generations = 1: rounds 1, 2
    SCREENSHOTS.mkdir(exist_ok=True)

    # ---- trial 1, generation 0, keyboard only ----
    ids = shown_faces(page)
    shown.append((0, 0, 0, ids))
    boxes = page.eval_on_selector_all(
        "#grid > .cell", "cs => cs.map(c => JSON.stringify(c.getBoundingClientRect()))"
    )
    page.focus("#grid > .cell:nth-child(1) .face")
    page.keyboard.press("ArrowRight")
    page.keyboard.press("ArrowRight")  # face 3
    page.keyboard.press("Enter")  # first selection: best
    page.keyboard.press("ArrowDown")  # face 8
    page.keyboard.press("Space")  # also acceptable
    page.keyboard.press("b")  # …no: make face 8 the best (3 becomes acceptable)
    assert page.get_attribute("#grid > .cell:nth-child(8)", "data-role") == "best"
    assert page.get_attribute("#grid > .cell:nth-child(3)", "data-role") == "ok"
    page.screenshot(path=str(SCREENSHOTS / "trial-1366x768.png"))
    # the selection survives a reload (kept until submitted)
    page.reload()
    wait_ready(page, "trial")
    assert shown_faces(page) == ids
    assert page.get_attribute("#grid > .cell:nth-child(8)", "data-role") == "best"
    page.focus("#next")
    page.keyboard.press("Enter")
    chosen.append((0, 0, 0, ids[7], [ids[2]]))
    wait_for(page, "document.querySelector('#progress').innerText.includes('Round 2 of 2')")
    wait_ready(page, "trial")

    # ---- trial 1, generation 1: min 2 and max 3 selections enforced in the page ----
    ids = shown_faces(page)
    shown.append((0, 0, 1, ids))
    page.click("#grid > .cell:nth-child(1) .face")
    assert page.is_disabled("#next")  # 1 < min_selections
    for n in (2, 4, 5):
        page.click(f"#grid > .cell:nth-child({n}) .face")
    assert page.get_attribute("#grid > .cell:nth-child(5)", "data-role") == "none"  # 4th refused
    assert "at most 3" in page.inner_text("#message")
    page.click("#next")
    chosen.append((0, 0, 1, ids[0], [ids[1], ids[3]]))

    # ---- rating of trial 1 ----
    wait_ready(page, "rating")
    # the prompt stays the heading; the rating's own question is the scale's legend
    assert page.inner_text("#prompt") == "Make the face look HAPPY"
    assert page.inner_text("#rating-question") == (
        "How well does this face show the emotion you were asked for?"
    )
    page.screenshot(path=str(SCREENSHOTS / "rating-1366x768.png"))
    page.get_by_label("6", exact=True).check()
    page.click("#rate")

    # ---- a short pause before trial 2 says where the participant is; a tap skips it ----
    wait_for(page, "window.emogenStudy.stage === 'transition'", timeout=10_000)
    assert page.inner_text("#transition-text") == "Trial 2 of 2 — next: SAD"
    assert not page.evaluate("window.emogenStudy.ready")  # no faces yet: no clock running
    page.evaluate("document.getElementById('view-transition').click()")

    # ---- trial 2: a restart, then two generations with the mouse ----
    wait_for(page, "document.querySelector('#prompt').innerText.includes('SAD')")
    wait_ready(page, "trial")
    shown.append((1, 0, 0, shown_faces(page)))
    page.set_viewport_size({"width": 1024, "height": 768})
    page.click("#restart")
    wait_for(page, f"document.querySelector('#grid > .cell').dataset.face !== '{shown[-1][3][0]}'")
    wait_ready(page, "trial")
    for generation in (0, 1):
        ids = shown_faces(page)
        shown.append((1, 1, generation, ids))
        page.click("#grid > .cell:nth-child(10) .face")
        page.click("#grid > .cell:nth-child(9) .face")
        chosen.append((1, 1, generation, ids[9], [ids[8]]))
        if generation == 0:
            page.set_viewport_size({"width": 768, "height": 1024})
            page.screenshot(path=str(SCREENSHOTS / "trial-768x1024.png"))
        page.click("#next")
        wait_ready(page, "rating" if generation == 1 else "trial")
    page.get_by_label("2", exact=True).check()
    page.click("#rate")
    wait_ready(page, "done")
    assert page.inner_text("#done-code") == "BROWSER-OK"
    page.screenshot(path=str(SCREENSHOTS / "done-768x1024.png"))
    assert page.evaluate("window.__shift") < 0.01, "layout shifted while faces loaded"
    del boxes
    assert errors == []
    assert page.evaluate("window.__cspViolations") == []
    context.close()

    # ---- the export holds every generation shown and every selection made ----
    store = Store(db_url)
    tables = export_tables(store)
    faces = tables["faces"]
    for trial, attempt, generation, ids in shown:
        rows = faces[
            (faces.trial == trial) & (faces.attempt == attempt) & (faces.generation == generation)
        ].sort_values("position")
        assert rows.face_id.tolist() == ids, (trial, attempt, generation)
    assert len(faces) == 10 * len(shown)
    sel = tables["selections"]
    for trial, attempt, generation, elite, others in chosen:
        rows = sel[
            (sel.trial == trial) & (sel.attempt == attempt) & (sel.generation == generation)
        ].sort_values("rank")
        assert rows.face_id.tolist() == [elite, *others], (trial, generation)
        assert rows.role.tolist() == ["elite"] + ["other"] * len(others)
        assert (rows.client_response_ms > 0).all()
        # the page reports how long its faces took to draw (then not counted as response time)
        assert rows.load_ms.notna().all() and (rows.load_ms > 0).all(), rows.load_ms.tolist()
        assert (rows.load_ms < 60_000).all()
    assert len(sel) == sum(1 + len(c[4]) for c in chosen)
    assert len(tables["restarts"]) == 1
    assert tables["restarts"].load_ms.notna().all() and (tables["restarts"].load_ms > 0).all()
    assert tables["evolve_ratings"].value.tolist() == [6, 2]
    assert tables["sessions"].stage.tolist() == ["done"]
    assert replay_session(store, 1, ict_model.rig, ict_model.model_hash, model=ict_model).ok
    store.dispose()

    # ---- and `emogen analyse` reads that export end to end ----
    from typer.testing import CliRunner

    from emogen.cli import app
    from emogen.study.export import write_export

    write_export(tables, tmp_path / "export")
    result = CliRunner().invoke(
        app,
        [
            "analyse",
            str(tmp_path / "export"),
            "--out",
            str(tmp_path / "analysis"),
            "--model",
            str(ict_dir),
            "--noise-runs",
            "50",
        ],
    )
    assert result.exit_code == 0, result.output
    assert (tmp_path / "analysis" / "index.html").is_file()
