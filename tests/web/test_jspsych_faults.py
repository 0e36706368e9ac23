"""The jsPsych plugin on the real internet (#40), in Debian's Chromium: a lab's page on one
origin, ``emogen serve`` on another behind a fault-injecting proxy (tests/web/fault_proxy.py).

- an outage of 6 s mid-evolve: the step is retried with its idempotency key, every remaining
  trial runs in the study's order and the session completes; jsPsych's Prolific recipe
  (``addProperties({subject_id, study_id, session_id})``) overwrites none of the plugin's fields,
  and every row — a failed one too — joins the export on ``emogen_session_id``/``emogen_trial``;
- a listener that never answers, a frozen server (SIGSTOP): each trial fails as ``timeout``
  within its documented deadline, saying so to the participant in their words;
- a reload mid-categorise and a reopened link in a new tab: the plugin follows the server
  (the trials the session has passed are not re-run, the old tab gives way); a study that
  resumes only by link refuses the new tab with a recorded reason; a bad ``server`` value
  shows the failure screen.
"""

from __future__ import annotations

import os
import re
import signal
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from benchmarks.bench_study import ServerProcess
from benchmarks.jspsych_site import ExperimentSite, one_trial_page
from playwright.sync_api import TimeoutError as PlaywrightTimeout

from emogen.study.export import export_tables
from emogen.study.storage import Store
from tests.web.fault_proxy import FaultProxy, SilentListener
from tests.web.test_jspsych_browser import open_page, serve, shot, site
from tests.web.test_study_browser import browser, viewer_bundle

pytestmark = [pytest.mark.browser, pytest.mark.slow]
_ = (browser, viewer_bundle, site)  # fixtures, requested by name

#: The issue's study: two evolve trials, then three categorise trials.
STUDY: dict[str, Any] = {
    "name": "outages",
    "emotions": ["happy", "sad"],
    "identities": ["female-medium"],
    "seed": 40,
    "order": "fixed",
    "resume": "participant_id",
    "ga": {"generations": 1, "min_selections": 2, "max_selections": 3},
    "blocks": [
        {"task": "evolve", "name": "make", "order": "fixed"},
        {"task": "categorise", "name": "recognise", "own": True, "random": 1},
    ],
}
TIMELINE = [{"task": "evolve"}] * 2 + [{"task": "categorise"}] * 3
#: jsPsych's documented Prolific recipe.
PROLIFIC = """jsPsych.data.addProperties({
  subject_id: jsPsych.data.getURLVariable("PROLIFIC_PID"),
  study_id: jsPsych.data.getURLVariable("STUDY_ID"),
  session_id: jsPsych.data.getURLVariable("SESSION_ID"),
});"""
ANY_READY = ".emogen-trial[data-emogen-ready='true']"


@pytest.fixture
def served(
    site: ExperimentSite, tmp_path: Path, ict_dir: Path, viewer_bundle: Path
) -> Iterator[tuple[ServerProcess, FaultProxy, str]]:
    srv, url = serve(STUDY, site, tmp_path, ict_dir)
    proxy = FaultProxy(srv.port)
    yield srv, proxy, url
    proxy.close()
    for pid in srv.pids():  # a test that froze it
        os.kill(pid, signal.SIGCONT)
    srv.stop()


def rows(page: Any) -> list[dict[str, Any]]:
    return page.evaluate("jsPsych.data.get().values()")  # type: ignore[no-any-return]


def step_once(page: Any, timeout: float = 60_000) -> str:
    """One response at whatever emogen screen is ready: two faces and Next, the rating, or the
    first label. Returns the screen."""
    page.wait_for_selector(ANY_READY, timeout=timeout)
    stage = page.get_attribute(".emogen-trial", "data-emogen-stage")
    if stage == "trial":
        cells = page.locator("#grid > .cell .face")
        cells.nth(0).click()
        cells.nth(1).click()
        page.click("#next")
    elif stage == "rating":
        page.locator("#rating-scale").get_by_label("5", exact=True).check()
        page.click("#rate")
    elif stage == "categorise":
        page.click("#label-buttons button:nth-child(1)")
    return str(stage)


def run_to_end(page: Any) -> None:
    while not page.evaluate("window.done === true"):
        if page.locator(".emogen-trial[data-emogen-stage='failed']").count():
            page.click("#failed-continue")
            continue
        try:
            step_once(page, timeout=5_000)
        except PlaywrightTimeout:  # between trials, or the end: look again
            continue


def joined(url: str) -> tuple[Any, Any]:
    """The export's sessions and trials tables."""
    store = Store(url)
    tables = export_tables(store)
    store.dispose()
    return tables["sessions"], tables["trials"]


def test_an_outage_mid_evolve_and_the_prolific_recipe(
    browser: Any, site: ExperimentSite, served: tuple[ServerProcess, FaultProxy, str]
) -> None:
    _srv, proxy, url = served
    query = "?PROLIFIC_PID=outage-1&STUDY_ID=st-9&SESSION_ID=prolific-session-3"
    page_url = site.add("outage.html", one_trial_page(proxy.url, TIMELINE, PROLIFIC)) + query
    page = open_page(browser, page_url, (1366, 768))
    assert step_once(page) == "trial"  # generation 0 of the happy trial
    page.wait_for_selector(ANY_READY + "[data-emogen-stage='trial']", timeout=60_000)
    timer = proxy.outage(6.0)  # the server unreachable for 6 s, mid-trial
    started = time.monotonic()
    assert step_once(page) == "trial"
    page.wait_for_selector("text=Connection lost", timeout=10_000)  # said while retrying
    page.wait_for_selector(ANY_READY + "[data-emogen-stage='rating']", timeout=60_000)
    assert time.monotonic() - started >= 5.5  # the step went through after the outage
    timer.join()
    run_to_end(page)
    data = rows(page)
    page.context.close()

    assert [r["emogen_success"] for r in data] == [True] * 5, [r["emogen_reason"] for r in data]
    assert [r["emogen_trial"] for r in data] == [0, 1, 2, 3, 4]  # the study's order
    assert [r["emogen_task"] for r in data] == [t["task"] for t in TIMELINE]
    assert [r["emogen_emotion"] for r in data[:2]] == ["happy", "sad"]
    # the recipe's fields are the lab's; the plugin's are namespaced and intact
    assert {r["session_id"] for r in data} == {"prolific-session-3"}
    assert {r["subject_id"] for r in data} == {"outage-1"}
    sessions, trials = joined(url)
    (sid,) = sessions.query("participant_id == 'outage-1'")["session_id"]
    assert {r["emogen_session_id"] for r in data} == {sid}
    assert sessions.set_index("session_id").loc[sid, "stage"] == "done"
    done = trials.query("session_id == @sid").set_index("trial")
    for r in data:  # every row joins the export on the namespaced ids
        assert done.loc[r["emogen_trial"], "task"] == r["emogen_task"]
        assert done.loc[r["emogen_trial"], "status"] == "done"
    assert (
        data[0]["rt"]
        == sum(g["rt"] for g in data[0]["emogen_generations"]) + (data[0]["emogen_rating_rt"])
    )
    assert data[2]["rt"] == data[2]["emogen_response_rt"]


def test_an_outage_longer_than_patience_and_try_again(
    browser: Any, site: ExperimentSite, served: tuple[ServerProcess, FaultProxy, str]
) -> None:
    _srv, proxy, url = served
    timeline = [{**t, "patience_ms": 2500} for t in TIMELINE]
    page_url = site.add("longer.html", one_trial_page(proxy.url, timeline)) + "?PROLIFIC_PID=long-1"
    page = open_page(browser, page_url, (1366, 768))
    assert step_once(page) == "trial"  # generation 0 of the happy trial
    page.wait_for_selector(ANY_READY + "[data-emogen-stage='trial']", timeout=60_000)
    proxy.down()  # past patience_ms: the trial fails
    assert step_once(page) == "trial"
    page.wait_for_selector(".emogen-trial[data-emogen-stage='failed']", timeout=30_000)
    assert page.locator("#failed-retry").is_visible()
    assert "Try again once you are back online" in page.inner_text("#failed-next")
    shot(page, "jspsych_try_again_1366x768.png")
    proxy.up()
    page.click("#failed-retry")
    # the same trial, where the session is: generation 1 (the 3D viewer is reused)
    page.wait_for_selector(ANY_READY + "[data-emogen-stage='trial']", timeout=60_000)
    run_to_end(page)
    data = rows(page)
    page.context.close()
    assert [r["emogen_success"] for r in data] == [True] * 5, [r["emogen_reason"] for r in data]
    assert [r["emogen_trial"] for r in data] == [0, 1, 2, 3, 4]  # no emogen slot lost
    assert [r["emogen_tries"] for r in data] == [2, 1, 1, 1, 1]
    first = data[0]["emogen_generations"]
    assert [g["generation"] for g in first] == [0, 1]  # both runs' steps in the one row
    sessions, _trials = joined(url)
    (sid,) = sessions.query("participant_id == 'long-1'")["session_id"]
    assert sessions.set_index("session_id").loc[sid, "stage"] == "done"
    store = Store(url)
    chosen = export_tables(store)["selections"].query("session_id == @sid and trial == 0")
    store.dispose()
    elites = chosen.query("role == 'elite'").sort_values("generation")["face_id"].tolist()
    assert elites == [g["elite"] for g in first]


def failed_row(page: Any) -> tuple[dict[str, Any], str]:
    page.wait_for_selector(".emogen-trial[data-emogen-stage='failed']", timeout=60_000)
    said = page.inner_text("#failed-reason")
    page.click("#failed-continue")
    page.wait_for_function("jsPsych.data.get().count() >= 1", timeout=30_000)
    return rows(page)[-1], said


def test_a_listener_that_never_answers_and_a_frozen_server_end_in_time(
    browser: Any, site: ExperimentSite, served: tuple[ServerProcess, FaultProxy, str]
) -> None:
    srv, proxy, url = served
    deadline = {"timeout_ms": 2000, "patience_ms": 6000}
    with SilentListener() as silent:
        site.add("silent.html", one_trial_page(silent.url, [{"task": "evolve", **deadline}]))
        page = open_page(browser, f"{site.origin}/silent.html?PROLIFIC_PID=silent-1", (390, 844))
        row, said = failed_row(page)
        page.context.close()
    assert row["emogen_failure"] == "timeout"
    assert re.search(r"did not answer /api/study within [4-6] s", row["emogen_reason"])
    assert "connection to the study was lost" in said and "/api" not in said
    assert row["emogen_duration_ms"] < 6000 + 3000  # the deadline, and the Continue click

    site.add("frozen.html", one_trial_page(proxy.url, [{"task": "evolve", **deadline}]))
    page = open_page(browser, f"{site.origin}/frozen.html?PROLIFIC_PID=frozen-1", (1366, 768))
    page.wait_for_selector(ANY_READY + "[data-emogen-stage='trial']", timeout=60_000)
    for pid in srv.pids():
        os.kill(pid, signal.SIGSTOP)  # the server freezes while the faces are shown
    started = time.monotonic()
    assert step_once(page) == "trial"
    page.wait_for_selector(".emogen-trial[data-emogen-stage='failed']", timeout=30_000)
    waited = time.monotonic() - started
    shot(page, "jspsych_server_frozen_1366x768.png")
    for pid in srv.pids():
        os.kill(pid, signal.SIGCONT)
    row, _said = failed_row(page)
    page.context.close()
    assert 3.0 <= waited <= 6.0 + 3.0, waited  # patience_ms, not for ever
    assert row["emogen_failure"] == "timeout"
    assert re.search(r"did not answer /api/s/…/step within [4-6] s", row["emogen_reason"])
    sessions, _trials = joined(url)
    assert (
        row["emogen_session_id"]
        == sessions.query("participant_id == 'frozen-1'")["session_id"].item()
    )  # the failed row carries its session


def test_a_reload_mid_categorise_and_a_reopened_link_follow_the_server(
    browser: Any, site: ExperimentSite, served: tuple[ServerProcess, FaultProxy, str]
) -> None:
    _srv, proxy, url = served
    page_url = site.add("reopen.html", one_trial_page(proxy.url, TIMELINE))
    page = open_page(browser, f"{page_url}?PROLIFIC_PID=reload-1", (1366, 768))
    while step_once(page) != "categorise":  # both evolve trials, then the first label
        pass
    page.wait_for_selector(ANY_READY + "[data-emogen-stage='categorise']", timeout=60_000)
    page.reload()  # mid-categorise (trial 4 of 5): jsPsych starts its timeline again
    run_to_end(page)
    after = rows(page)
    page.context.close()
    # the first two emogen trials run the session's trials 3 and 4; the others find it done
    assert [r["emogen_trial"] for r in after[:2]] == [3, 4]
    assert [r["emogen_task"] for r in after[:2]] == ["categorise", "categorise"]
    assert [r["emogen_timeline_task"] for r in after[:2]] == ["evolve", "evolve"]
    assert [r["emogen_failure"] for r in after[2:]] == ["finished"] * 3
    assert len({r["emogen_session_id"] for r in after}) == 1

    # a reopened link in a new tab: the same session, the old tab gives way
    context = browser.new_context(viewport={"width": 390, "height": 844})
    first = context.new_page()
    first.goto(f"{page_url}?PROLIFIC_PID=tabs-1")
    assert step_once(first) == "trial"
    first.wait_for_selector(ANY_READY + "[data-emogen-stage='trial']", timeout=60_000)
    second = context.new_page()
    second.goto(f"{page_url}?PROLIFIC_PID=tabs-1")
    second.wait_for_selector(ANY_READY + "[data-emogen-stage='trial']", timeout=60_000)
    first.wait_for_selector(".emogen-trial[data-emogen-stage='failed']", timeout=30_000)
    assert "Please close this tab" in first.inner_text("#failed-reason")
    assert not first.locator("#failed-continue").is_visible()  # nothing to go on with here
    shot(first, "jspsych_other_tab_390x844.png")
    assert second.inner_text("#gen-progress") == "Round 2 of 2"  # where the first tab was
    run_to_end(second)
    new = rows(second)
    context.close()
    assert [r["emogen_trial"] for r in new] == [0, 1, 2, 3, 4]
    assert all(r["emogen_success"] for r in new)
    sessions, _ = joined(url)
    tabs = sessions.query("participant_id == 'tabs-1'")  # one session, carried on and done
    assert tabs["stage"].tolist() == ["done"]
    assert tabs["session_id"].tolist() == [new[0]["emogen_session_id"]]


def test_a_study_that_resumes_by_link_only_and_a_bad_server_value(
    browser: Any, site: ExperimentSite, tmp_path: Path, ict_dir: Path, viewer_bundle: Path
) -> None:
    srv, _url = serve({**STUDY, "resume": "link"}, site, tmp_path, ict_dir)
    try:
        page_url = site.add("link.html", one_trial_page(srv.url, [{"task": "evolve"}]))
        context = browser.new_context(viewport={"width": 1366, "height": 768})
        first = context.new_page()
        first.goto(f"{page_url}?PROLIFIC_PID=link-1")
        first.wait_for_selector(ANY_READY, timeout=60_000)
        second = context.new_page()
        second.goto(f"{page_url}?PROLIFIC_PID=link-1")
        row, said = failed_row(second)
        context.close()
        assert row["emogen_failure"] == "resume"
        assert 'set resume = "participant_id"' in row["emogen_reason"]
        assert "resume" not in said and "not your fault" in said
    finally:
        srv.stop()
    site.add("bad.html", one_trial_page("study.example.org", [{"task": "evolve"}]))
    page = open_page(browser, f"{site.origin}/bad.html", (1366, 768))
    row, said = failed_row(page)
    page.context.close()
    assert row["emogen_failure"] == "server" and 'got "study.example.org"' in row["emogen_reason"]
