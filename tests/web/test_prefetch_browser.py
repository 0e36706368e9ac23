"""The next identity's face model made ahead (issue #39): in Debian's Chromium (Playwright), a
study of two evolve blocks on two identities, walked to the first trial of the second identity.

While the participant is on the last trial of the first identity the page builds the second
identity's model (download, parsing, upload to the GPU) unseen; at the switch the page only
draws the faces. Checked from the page's own record of the models it built
(``window.emogenStudy.loads``) — not from a timing that the machine's load moves — and, as a
bound, the switch step's time against the build it no longer waits for. A model made ahead that
fails (the server answers 500) or is slow (its answer held back until the switch) still ends
in a working trial, with nothing said to the participant.
"""

from __future__ import annotations

import statistics
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest
from benchmarks.bench_study import ServerProcess, write_study_toml

from tests.web.test_study_browser import CSP_PROBE, browser, viewer_bundle, wait_for, wait_ready

pytestmark = [pytest.mark.browser, pytest.mark.slow]
_ = (browser, viewer_bundle)  # fixtures, requested by name

FIRST, SECOND = "female-medium", "male-medium"
SWITCH_STUDY: dict[str, Any] = {
    "name": "switch",
    "emotions": ["happy", "sad"],
    "identities": [FIRST, SECOND],
    "seed": 3,
    "ga": {"generations": 2, "min_selections": 1, "max_selections": 3},
    "blocks": [
        {"task": "evolve", "name": "first", "identities": [FIRST], "order": "fixed"},
        {"task": "evolve", "name": "second", "identities": [SECOND], "order": "fixed"},
    ],
}
MODEL_URL = f"**/api/model/{SECOND}.glb"


@pytest.fixture(scope="module")
def site(
    tmp_path_factory: pytest.TempPathFactory, ict_dir: Path, ict_model, viewer_bundle: Path
) -> Iterator[ServerProcess]:
    tmp = tmp_path_factory.mktemp("switch")
    config = write_study_toml(SWITCH_STUDY, tmp / "switch.toml")
    srv = ServerProcess(config, f"sqlite:///{tmp / 'study.sqlite'}", ict_dir, tmp / "log").start()
    yield srv
    srv.stop()


def open_study(browser: Any, srv: ServerProcess, pid: str) -> tuple[Any, list[str]]:
    page = browser.new_context(viewport={"width": 1366, "height": 768}).new_page()
    page.add_init_script(CSP_PROBE)
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(f"{srv.url}/?PROLIFIC_PID={pid}")
    page.get_by_role("button", name="I agree").click()
    wait_ready(page, "instructions")
    page.get_by_role("button", name="Begin").click()
    return page, errors


def identity(page: Any, srv: ServerProcess) -> str:
    """The identity of the trial the server says the participant is on."""
    token = page.url.split("/s/")[1].split("?")[0]
    state = httpx.get(f"{srv.url}/api/s/{token}/state", timeout=30).json()
    return str(state["trial"]["identity"])


def loads(page: Any) -> list[dict[str, Any]]:
    return page.evaluate("() => window.emogenStudy.loads.map((l) => ({...l}))")


def next_screen(page: Any, before: str) -> float:
    """Wait for the screen after ``before`` (its progress line) to be ready; its ready time in
    ms as the page measures it (the step's answer, after any pause between trials, to the
    faces drawn: the load time the page reports with the next step)."""
    wait_for(page, f"document.getElementById('progress').innerText !== {before!r}", 60_000)
    wait_for(page, "window.emogenStudy.ready", 120_000)
    return float(page.evaluate("() => window.emogenStudy.loadMs"))


def round_step(page: Any) -> float:
    """One evolve round answered (faces 1 and 2, Next); the next screen's ready time (ms)."""
    wait_ready(page, "trial")
    before = page.inner_text("#progress")
    page.click("#grid > .cell:nth-child(1) .face")
    page.click("#grid > .cell:nth-child(2) .face")
    page.click("#next")
    return next_screen(page, before)


def rate(page: Any) -> float:
    """The rating answered (5); the next screen's ready time (ms)."""
    wait_ready(page, "rating")
    before = page.inner_text("#progress")
    page.get_by_label("5", exact=True).check()
    page.click("#rate")
    return next_screen(page, before)


def walk_first_identity(page: Any) -> list[float]:
    """Both trials of the first identity, all but the last rating; the screens' ready times."""
    times = [round_step(page) for _ in range(3)]  # trial 1: 3 rounds (2 generations + final)
    times.append(rate(page))
    times += [round_step(page) for _ in range(3)]  # trial 2: the model of SECOND made meanwhile
    return times


def test_the_next_identity_is_ready_at_the_switch(site: ServerProcess, browser: Any) -> None:
    page, errors = open_study(browser, site, "switch-1")
    times = walk_first_identity(page)
    wait_ready(page, "rating")
    made = loads(page)
    ahead = [m for m in made if m["url"].endswith(f"/{SECOND}.glb")]
    # made ahead in both of the page's face containers (the round grid, the rating face), and
    # finished before the switch
    assert len(ahead) == 2 and all(m["ahead"] for m in ahead), made
    first_build = max(m["total_ms"] for m in made if m["url"].endswith(f"/{FIRST}.glb"))
    switch = rate(page)
    assert identity(page, site) == SECOND
    after = loads(page)
    assert after == made, f"a model was built at the switch: {after[len(made) :]}"
    # The bound: the first screen of the new identity is ready as fast as an ordinary screen
    # (ten faces drawn) plus the new container's first draw, not that plus a model build (the
    # first identity's build on this page, on this machine now). A build at the switch costs a
    # whole build and the first draw on top of an ordinary screen; the first draw alone took
    # 183–293 ms against builds of 480–690 ms (half a build as the margin failed once in a
    # fresh-clone CI run: 293 ms against 37 + 242), so the bound is one build.
    typical = statistics.median(times)
    assert switch < typical + first_build, (switch, times, first_build)
    assert page.evaluate("() => document.querySelectorAll('#grid .faces-canvas').length") == 2
    visible = page.eval_on_selector_all(
        "#grid .faces-canvas", "cs => cs.filter((c) => c.style.visibility !== 'hidden').length"
    )
    assert visible == 1
    assert page.inner_text("#message") == ""
    assert errors == []
    assert page.evaluate("() => window.__cspViolations") == []


@pytest.mark.parametrize("fault", ["500", "slow"])
def test_a_failed_or_slow_model_made_ahead_still_ends_in_a_working_trial(
    site: ServerProcess, browser: Any, fault: str
) -> None:
    page, errors = open_study(browser, site, f"switch-{fault}")
    asked: list[Any] = []
    failing = [True]  # until the participant reaches the switch

    def answer(route: Any) -> None:
        asked.append(route)
        if not failing[0]:
            route.continue_()
        elif fault == "500":
            route.fulfill(status=500, body="Internal Server Error")
        # slow: held until the participant reaches the switch

    page.route(MODEL_URL, answer)
    walk_first_identity(page)
    wait_ready(page, "rating")
    tried = len(asked)
    if fault == "slow":
        assert tried == 1  # asked for once (the download is shared by both grids), held
    else:
        assert tried >= 1  # tried ahead (again at each screen after a failure), every try 500
    page.get_by_label("5", exact=True).check()
    failing[0] = False
    page.click("#rate")
    if fault == "slow":
        wait_for(page, "window.emogenStudy.stage === 'trial' && !window.emogenStudy.ready")
        page.wait_for_timeout(1000)
        assert not page.evaluate("() => window.emogenStudy.ready")  # waiting on the held model
        asked[0].continue_()
    wait_ready(page, "trial")
    assert identity(page, site) == SECOND
    built = [m for m in loads(page) if m["url"].endswith(f"/{SECOND}.glb")]
    if fault == "500":
        # asked again when shown, as without a model made ahead (a retry ahead, for another
        # container, may also land once the fault has cleared: it is then built, and fine)
        assert len(asked) >= tried + 1
        assert False in [m["ahead"] for m in built]  # the shown one was built when shown
    else:
        # both containers' models were made ahead from the one held download; the one not
        # shown may finish after the trial is ready (seen once in a fresh-clone CI run)
        both = (
            f"window.emogenStudy.loads.filter((l) => l.url.endsWith('/{SECOND}.glb')).length >= 2"
        )
        wait_for(page, both, 60_000)
        built = [m for m in loads(page) if m["url"].endswith(f"/{SECOND}.glb")]
        assert len(asked) == 1 and [m["ahead"] for m in built] == [True, True]
    assert page.inner_text("#message") == ""  # nothing said to the participant
    # the trial works: the next round is answered with the new identity's faces
    round_step(page)
    assert identity(page, site) == SECOND
    assert errors == []
