"""A study of three blocks — two evolve blocks (four emotions on one identity each) and a
categorise block (the participant's own faces, other participants' and random ones) — completed
in Debian's Chromium (Playwright) on a desktop (3D viewer, keyboard) and a phone (3D viewer,
touch-sized clicks), and the categorise screen with the server's images (no WebGL).

What the page answered is what the export holds, face for face: the labels chosen, the ratings,
the response and load times, the face shown (its weights: the participant's own final face,
another participant's, a random draw) — and the session replays.

Screenshots go to /tmp/emogen-blocks-screenshots; ``EMOGEN_UPDATE_SCREENSHOTS=1`` writes the
ones docs/study.md shows (docs/images/categorise_<w>x<h>.jpg).
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import numpy as np
import pandas as pd
import pytest
from benchmarks.bench_study import ServerProcess, write_study_toml

from emogen.study.export import export_tables
from emogen.study.replay import replay_session
from emogen.study.storage import Store
from tests.study.drive import command, run_to_end
from tests.web.test_devices import inside_viewport, no_horizontal_overflow
from tests.web.test_study_browser import CSP_PROBE, browser, viewer_bundle, wait_for, wait_ready
from tests.web.viewer_site import screenshot_folder

pytestmark = [pytest.mark.browser, pytest.mark.slow]
_ = (browser, viewer_bundle)  # fixtures, requested by name

SCREENSHOTS = screenshot_folder("blocks")
BLOCKS_STUDY: dict[str, Any] = {
    "name": "blocks",
    "emotions": ["happy", "sad", "angry", "fearful"],
    "identities": ["female-medium", "male-medium"],
    "seed": 5,
    "ga": {"generations": 1, "min_selections": 1, "max_selections": 3},
    "completion": {"code": "BLOCKS-OK"},
    "blocks": [
        {
            "task": "evolve",
            "name": "make_female",
            "identities": ["female-medium"],
            "order": "fixed",
        },
        {"task": "evolve", "name": "make_male", "identities": ["male-medium"], "order": "fixed"},
        {
            "task": "categorise",
            "name": "recognise",
            "own": True,
            "others": 2,
            "random": 2,
            "none_option": True,
            "intensity": True,
            "confidence": True,
        },
    ],
}
N_EVOLVE = 4 * 2  # four emotions on each of two identities
N_CATEGORISE = N_EVOLVE + 2 + 2


@pytest.fixture(scope="module")
def site(
    tmp_path_factory: pytest.TempPathFactory, ict_dir: Path, ict_model, viewer_bundle: Path
) -> Iterator[tuple[ServerProcess, str]]:  # type: ignore[no-untyped-def]
    """One server (SQLite) for the module, with one participant completed over HTTP first (so
    that 'others' faces come from a completed session, not the fallback)."""
    tmp = tmp_path_factory.mktemp("blocks")
    config = write_study_toml(BLOCKS_STUDY, tmp / "blocks.toml")
    url = f"sqlite:///{tmp / 'study.sqlite'}"
    srv = ServerProcess(config, url, ict_dir, tmp / "server.log").start()

    def post(path: str, body: dict[str, Any]) -> dict[str, Any]:
        r = httpx.post(f"{srv.url}{path}", json=body, timeout=60)
        assert r.status_code in (200, 201), r.text
        return r.json()  # type: ignore[no-any-return]

    token = post("/api/sessions", {"participant_id": "first"})["token"]
    state = httpx.get(f"{srv.url}/api/s/{token}/state", timeout=30).json()
    done = run_to_end(state, lambda kind, body: post(f"/api/s/{token}/step", command(kind, body)))
    assert done["stage"] == "done"
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
    token = page.url.split("/s/")[1].split("?")[0]
    return httpx.get(f"{srv.url}/api/s/{token}/state", timeout=30).json()  # type: ignore[no-any-return]


def evolve_trials(page: Any, n: int) -> None:
    """Each trial: the first face, then the second (best + one), both generations; rate 5."""
    for _ in range(n):
        for _generation in range(2):
            wait_ready(page, "trial")
            page.click("#grid > .cell:nth-child(1) .face")
            page.click("#grid > .cell:nth-child(2) .face")
            page.click("#next")
        wait_ready(page, "rating")
        page.get_by_label("5", exact=True).check()
        page.click("#rate")


def labels_shown(page: Any) -> list[str]:
    return page.eval_on_selector_all(  # type: ignore[no-any-return]
        "#label-buttons button", "bs => bs.map(b => b.dataset.label)"
    )


def check_categorise_layout(page: Any) -> None:
    page.evaluate("scrollTo(0, 0)")
    no_horizontal_overflow(page)
    inside_viewport(page, "#prompt")
    face = inside_viewport(page, ".categorise-face")
    short = min(page.viewport_size["width"], page.viewport_size["height"])
    assert face["width"] >= min(0.6 * short, 300), face  # large: bigger than a GA tile
    for i in range(len(labels_shown(page))):
        inside_viewport(page, f"#label-buttons button:nth-child({i + 1})")
    page.evaluate("scrollTo(0, 0)")


@pytest.mark.parametrize(
    ("size", "keyboard"), [((1366, 768), True), ((390, 844), False)], ids=["desktop", "phone"]
)
def test_a_study_of_evolve_and_categorise_blocks_runs_to_completion(
    browser: Any, site: tuple[ServerProcess, str], ict_model, size: tuple[int, int], keyboard: bool
) -> None:  # type: ignore[no-untyped-def]
    srv, url = site
    pid = f"blocks-{size[0]}"
    page = start(browser, srv, size, pid, has_touch=not keyboard, is_mobile=not keyboard)
    wait_ready(page, "trial")
    assert page.evaluate("window.emogenStudy.display") == "webgl"
    evolve_trials(page, N_EVOLVE)
    answered: list[dict[str, Any]] = []
    for k in range(N_CATEGORISE):
        wait_ready(page, "categorise")
        state = state_of(page, srv)
        view = state["view"]
        assert view["task"] == "categorise" and "emotion" not in view  # not given away
        labels = labels_shown(page)
        assert labels == [*view["labels"], "none"]  # in the order drawn, "none of these" last
        assert page.inner_text("#prompt") == "Which emotion does this face show?"
        total = N_EVOLVE + N_CATEGORISE
        assert f"Trial {N_EVOLVE + 1 + k} of {total}" in page.inner_text("#progress")
        assert "Part 3 of 3" in page.inner_text("#progress")
        assert page.is_hidden("#intensity-set") and page.is_hidden("#confidence-set")
        assert page.is_disabled("#answer")
        pick = (k % 5) + 1  # "none of these" (5th) too: it asks no intensity
        rated = labels[pick - 1] != "none"
        if k == 0:
            check_categorise_layout(page)
        if keyboard:
            page.keyboard.press(str(pick))
        else:
            page.click(f"#label-buttons button:nth-child({pick})")
        button = page.locator(f"#label-buttons button:nth-child({pick})")
        assert button.get_attribute("aria-pressed") == "true"
        assert page.is_visible("#intensity-set") == rated and page.is_visible("#confidence-set")
        assert page.is_disabled("#answer")  # the ratings are still missing
        asked = "how intense it is and how sure you are" if rated else "how sure you are"
        assert f"Now say {asked}," in page.inner_text("#categorise-status")
        intensity, confidence = (1 + k % 7 if rated else None), 7 - k % 7
        intensity_scale = page.locator("#intensity-scale")
        if k == 1:  # a reload keeps the answer given so far (until it is sent)
            intensity_scale.get_by_label(str(intensity), exact=True).check()
            page.reload()
            wait_ready(page, "categorise")
            assert button.get_attribute("aria-pressed") == "true"
            assert intensity_scale.get_by_label(str(intensity), exact=True).is_checked()
        if keyboard:  # in a scale, the number keys give the rating
            if rated:
                intensity_scale.locator("input").first.focus()
                page.keyboard.press(str(intensity))
            page.locator("#confidence-scale input").first.focus()
            page.keyboard.press(str(confidence))
            assert button.get_attribute("aria-pressed") == "true"  # the label stays
        else:
            if rated:
                intensity_scale.get_by_label(str(intensity), exact=True).check()
            page.locator("#confidence-scale").get_by_label(str(confidence), exact=True).check()
        assert page.is_enabled("#answer")
        if k == 0:
            SCREENSHOTS.mkdir(parents=True, exist_ok=True)
            page.evaluate("scrollTo(0, 0)")
            page.screenshot(
                path=str(SCREENSHOTS / f"categorise_{size[0]}x{size[1]}.jpg"), quality=75
            )
            inside_viewport(page, "#answer")
        answered.append(
            {
                "trial": state["progress"]["trial"],
                "label": labels[pick - 1],
                "intensity": intensity,
                "confidence": confidence,
                "weights": view["face"]["weights"],
            }
        )
        if keyboard:
            page.focus("#answer")
            page.keyboard.press("Enter")
        else:
            page.click("#answer")
    wait_ready(page, "done")
    assert page.inner_text("#done-code") == "BLOCKS-OK"
    assert page.evaluate("window.__cspViolations") == []
    page.context.close()

    store = Store(url)
    tables = export_tables(store)
    sessions = tables["sessions"]
    session_id = int(sessions.loc[sessions.participant_id == pid, "session_id"].iloc[0])
    responses = (
        tables["categorise_responses"].query("session_id == @session_id").sort_values("trial")
    )
    assert responses["trial"].tolist() == [a["trial"] for a in answered]
    assert responses["label"].tolist() == [a["label"] for a in answered]
    given = [None if pd.isna(x) else int(x) for x in responses["intensity"]]
    assert given == [a["intensity"] for a in answered]  # none with "none of these"
    assert (responses["label"] == "none").sum() == N_CATEGORISE // 5
    assert responses["confidence"].tolist() == [a["confidence"] for a in answered]
    assert (responses["client_response_ms"] > 0).all() and (responses["load_ms"] > 0).all()
    assert sorted(responses["source"].value_counts().items()) == [
        ("other", 2),
        ("own", N_EVOLVE),
        ("random", 2),
    ]
    assert not responses["fallback"].any()  # a completed session was there to draw from
    w_cols = [c for c in responses.columns if c.startswith("w_")]
    shown = np.array([a["weights"] for a in answered])
    np.testing.assert_allclose(responses[w_cols].to_numpy(float), shown, atol=1e-12)
    # own faces: the participant's final faces, as the faces table holds them
    faces, trials = tables["faces"], tables["trials"]
    for _, r in responses.query("source == 'own'").iterrows():
        t = trials.query("session_id == @session_id and trial == @r.source_trial").iloc[0]
        final = faces.query(
            "session_id == @session_id and trial == @r.source_trial and face_id == @t.final_face_id"
        )
        np.testing.assert_allclose(final[w_cols].to_numpy(float)[-1], r[w_cols].to_numpy(float))
        assert r["identity"] == t["identity"] and r["intended"] == t["emotion"]
    others = responses.query("source == 'other'")
    assert set(others["source_participant_id"]) <= {"first", "blocks-1366"}
    report = replay_session(store, session_id, ict_model.rig, ict_model.model_hash, model=ict_model)
    assert report.ok and report.stimuli == N_CATEGORISE, report.mismatches
    store.dispose()


def test_the_categorise_screen_with_server_images(
    browser: Any, site: tuple[ServerProcess, str]
) -> None:
    """Without WebGL the face is the server's PNG of that trial's face: a new image each trial
    (face ids count from 0 in every trial, so the URL names the trial)."""
    srv, _url = site
    page = start(browser, srv, (360, 640), "blocks-png")
    wait_ready(page, "trial")
    page.goto(page.url.split("?")[0] + "?render=png")
    wait_ready(page, "trial")
    assert page.evaluate("window.emogenStudy.display") == "png"
    pngs: list[str] = []
    page.on("response", lambda r: pngs.append(r.url) if ".png" in r.url and r.ok else None)
    evolve_trials(page, N_EVOLVE)
    seen: list[str] = []
    for k in range(3):
        wait_ready(page, "categorise")
        src = page.get_attribute("#categorise-slot img", "src")
        assert src is not None and f"?trial={N_EVOLVE + k}&attempt=0" in src, src
        assert page.evaluate("document.querySelector('#categorise-slot img').naturalWidth") > 0
        seen.append(
            page.evaluate(
                "(() => { const i = document.querySelector('#categorise-slot img');"
                " const c = document.createElement('canvas'); c.width = 32; c.height = 32;"
                " const g = c.getContext('2d'); g.drawImage(i, 0, 0, 32, 32);"
                " return c.toDataURL(); })()"
            )
        )
        check_categorise_layout(page)
        page.click("#label-buttons button:nth-child(1)")
        page.locator("#intensity-scale").get_by_label("3", exact=True).check()
        page.locator("#confidence-scale").get_by_label("3", exact=True).check()
        page.click("#answer")
    assert len(set(seen)) == 3, "the same picture was shown for different faces"
    # every evolve generation's images were fetched for their own trial, not taken from cache
    grid_pngs = [u for u in pngs if "/faces/" in u and "trial=" in u]
    trials = {u.split("trial=")[1].split("&")[0] for u in grid_pngs}
    assert {str(t) for t in range(N_EVOLVE + 3)} <= trials, sorted(trials)
    # a face of another trial is not found (the URL names the trial)
    token = page.url.split("/s/")[1].split("?")[0]
    stale = httpx.get(f"{srv.url}/api/s/{token}/faces/0.png?trial=0&attempt=0", timeout=30)
    assert stale.status_code == 404 and "trial 0" in stale.json()["detail"]
    page.context.close()


#: A study that starts with its categorise block (random faces): the screen at once.
FIRST_STUDY: dict[str, Any] = {
    "name": "categorise-first",
    "emotions": ["happy", "sad", "angry", "fearful", "disgusted", "surprised"],
    "seed": 6,
    "blocks": [
        {
            "task": "categorise",
            "random": 2,
            "none_option": True,
            "intensity": True,
            "confidence": True,
        }
    ],
}
VIEWPORTS = [(360, 640), (390, 844), (768, 1024), (1366, 768), (2560, 1440)]


@pytest.fixture(scope="module")
def first_site(
    tmp_path_factory: pytest.TempPathFactory, ict_dir: Path, viewer_bundle: Path
) -> Iterator[ServerProcess]:
    tmp = tmp_path_factory.mktemp("first")
    config = write_study_toml(FIRST_STUDY, tmp / "first.toml")
    srv = ServerProcess(config, f"sqlite:///{tmp / 'study.sqlite'}", ict_dir, tmp / "server.log")
    yield srv.start()
    srv.stop()


@pytest.mark.parametrize(("width", "height"), VIEWPORTS, ids=[f"{w}x{h}" for w, h in VIEWPORTS])
def test_the_categorise_screen_fits_every_device(
    browser: Any, first_site: ServerProcess, width: int, height: int
) -> None:
    """Seven answers (six emotions and "none of these"), two rating scales and Continue, on
    phones, a tablet and desktops, upright and turned: nothing wider than the screen, every
    control reachable, the face large."""
    page = start(browser, first_site, (width, height), f"first-{width}x{height}")
    wait_ready(page, "categorise")
    assert page.evaluate("window.emogenStudy.display") == "webgl"
    assert len(labels_shown(page)) == 7
    check_categorise_layout(page)
    page.click("#label-buttons button:nth-child(7)")  # none of these: no intensity asked
    assert page.is_hidden("#intensity-set") and page.is_visible("#confidence-set")
    page.click("#label-buttons button:nth-child(2)")
    assert page.is_visible("#intensity-set")
    for name in ("intensity", "confidence"):
        page.locator(f"#{name}-scale").get_by_label("4", exact=True).check()
    for size in ((width, height), (height, width)):  # upright and turned
        page.set_viewport_size({"width": size[0], "height": size[1]})
        page.wait_for_timeout(100)
        check_categorise_layout(page)
        for selector in ("#intensity-scale", "#confidence-scale", "#answer"):
            inside_viewport(page, selector)
        no_horizontal_overflow(page)
    page.set_viewport_size({"width": width, "height": height})
    if width != 1366 and width != 390:  # those two are the blocks test's screenshots
        page.evaluate("scrollTo(0, 0)")
        SCREENSHOTS.mkdir(parents=True, exist_ok=True)
        page.screenshot(path=str(SCREENSHOTS / f"categorise_{width}x{height}.jpg"), quality=75)
    page.click("#answer")
    wait_for(page, "document.querySelector('#progress').innerText.includes('Trial 2 of 2')")
    wait_ready(page, "categorise")
    assert page.get_attribute("#label-buttons button:nth-child(2)", "aria-pressed") == "false"
    page.context.close()
