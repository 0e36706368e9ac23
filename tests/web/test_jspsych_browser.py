"""The jsPsych plugin in Debian's Chromium (Playwright), issue #31: the README's complete page —
a questionnaire, an evolve trial and a categorise trial — served by a lab's site on another
origin than ``emogen serve``, run to completion on a desktop and a phone; jsPsych's data and
``emogen study export`` agree session for session, and the sessions replay. Wrong use — a page
of an origin the study does not allow, a study without the block, the server gone mid-trial —
ends the trial with its reason in the page and in the data.

Screenshots go to /tmp/emogen-jspsych-screenshots; ``EMOGEN_UPDATE_SCREENSHOTS=1`` writes the
ones docs/jspsych.md shows (docs/images/jspsych_<task>_<w>x<h>.png).
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from benchmarks.bench_study import ServerProcess, write_study_toml
from benchmarks.jspsych_site import (
    ExperimentSite,
    build_plugin,
    local_page,
    one_trial_page,
    readme_page,
)

from emogen.study.export import export_tables
from emogen.study.replay import replay_session
from emogen.study.storage import Store
from tests.web.test_devices import no_horizontal_overflow
from tests.web.test_study_browser import browser, viewer_bundle
from tests.web.viewer_site import screenshot_folder

pytestmark = [pytest.mark.browser, pytest.mark.slow]
_ = (browser, viewer_bundle)  # fixtures, requested by name

SCREENSHOTS = screenshot_folder("jspsych")
STUDY: dict[str, Any] = {
    "name": "embedded",
    "emotions": ["happy", "sad", "angry", "fearful"],  # the labels of the categorise trial
    "identities": ["female-medium"],
    "seed": 31,
    "ga": {"generations": 2, "min_selections": 2, "max_selections": 3},
    "blocks": [
        {"task": "evolve", "name": "make", "emotions": ["happy"]},
        {"task": "categorise", "name": "recognise", "own": True},
    ],
}
READY = ".emogen-trial[data-emogen-ready='true'][data-emogen-stage='{}']"


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Iterator[ExperimentSite]:
    build_plugin()
    s = ExperimentSite(tmp_path_factory.mktemp("site"))
    yield s
    s.close()


def serve(
    study: dict[str, Any], site: ExperimentSite, tmp: Path, ict_dir: Path
) -> tuple[ServerProcess, str]:
    config = write_study_toml({**study, "embed_origins": [site.origin]}, tmp / "study.toml")
    url = f"sqlite:///{tmp / 'study.sqlite'}"
    return ServerProcess(config, url, ict_dir, tmp / "server.log").start(), url


@pytest.fixture(scope="module")
def server(
    tmp_path_factory: pytest.TempPathFactory,
    site: ExperimentSite,
    ict_dir: Path,
    viewer_bundle: Path,
) -> Iterator[tuple[ServerProcess, str]]:
    srv, url = serve(STUDY, site, tmp_path_factory.mktemp("server"), ict_dir)
    yield srv, url
    srv.stop()


def open_page(browser: Any, url: str, size: tuple[int, int], phone: bool = False) -> Any:
    context = browser.new_context(
        viewport={"width": size[0], "height": size[1]}, has_touch=phone, is_mobile=phone
    )
    page = context.new_page()
    page.on("pageerror", lambda e: pytest.fail(f"page error: {e}"))
    page.on("dialog", lambda d: d.accept())
    page.goto(url)
    return page


def wait_stage(page: Any, stage: str) -> None:
    page.wait_for_selector(READY.format(stage), timeout=60_000)


def shot(page: Any, name: str) -> None:
    SCREENSHOTS.mkdir(parents=True, exist_ok=True)
    page.evaluate("scrollTo(0, 0)")
    page.screenshot(path=str(SCREENSHOTS / name))


def jspsych_data(page: Any) -> list[dict[str, Any]]:
    """jsPsych's rows, the plugin's fields (``emogen_<name>``) by their plain names."""
    rows = page.evaluate("jsPsych.data.get().values()")
    return [{k.removeprefix("emogen_"): v for k, v in row.items()} for row in rows]


def run_readme_page(page: Any, size: tuple[int, int]) -> list[dict[str, Any]]:
    """The questionnaire, then an evolve trial (three generations, one "Start again", the
    rating), then a categorise trial (the participant's own final face)."""
    page.fill("#input-0", "34")
    page.click("#jspsych-survey-text-next")
    for g in range(3):
        wait_stage(page, "trial")
        cells = page.locator("#grid > .cell .face")
        assert cells.count() == 10
        if g == 0:
            no_horizontal_overflow(page)
            width = page.locator(".emogen-trial").bounding_box()["width"]
            cells.nth(0).click()  # the first click changes the help text: the trial keeps its width
            assert page.locator(".emogen-trial").bounding_box()["width"] == width
            cells.nth(0).click()
            shot(page, f"jspsych_evolve_{size[0]}x{size[1]}.png")
            page.click("#restart")  # a new attempt at generation 0
            wait_stage(page, "trial")
        cells.nth(g).click()
        cells.nth(g + 3).click()
        page.click("#next")
    wait_stage(page, "rating")
    page.locator("#rating-scale").get_by_label("6", exact=True).check()
    page.click("#rate")
    wait_stage(page, "categorise")
    no_horizontal_overflow(page)
    shot(page, f"jspsych_categorise_{size[0]}x{size[1]}.png")
    assert page.locator("#label-buttons button").count() == 4
    if size[0] > 700:  # a desktop: the labels beside the face, all in view without a scroll
        face = page.locator(".categorise-face").bounding_box()
        last = page.locator("#label-buttons button").nth(3).bounding_box()
        assert last["x"] >= face["x"] + face["width"]
        assert last["y"] + last["height"] <= size[1]
    page.click("#label-buttons button:nth-child(2)")
    page.wait_for_selector("#jspsych-data-display", timeout=30_000)  # on_finish: displayData
    return jspsych_data(page)


@pytest.mark.parametrize(
    ("size", "phone"), [((1366, 768), False), ((390, 844), True)], ids=["desktop", "phone"]
)
def test_the_readme_page_runs_and_its_data_agree_with_the_export(
    browser: Any,
    site: ExperimentSite,
    server: tuple[ServerProcess, str],
    ict_model: Any,
    size: tuple[int, int],
    phone: bool,
) -> None:
    srv, url = server
    pid = f"jspsych-{size[0]}"
    page = open_page(
        browser,
        site.add("faces.html", local_page(readme_page(), srv.url)) + f"?PROLIFIC_PID={pid}",
        size,
        phone,
    )
    survey, evolve, categorise = run_readme_page(page, size)
    page.context.close()
    assert survey["trial_type"] == "survey-text" and survey["response"] == {"age": "34"}
    assert evolve["trial_type"] == categorise["trial_type"] == "emogen"
    assert evolve["success"] and categorise["success"], (evolve["reason"], categorise["reason"])
    assert evolve["display"] == "webgl"
    assert evolve["session_id"] == categorise["session_id"]
    assert evolve["participant_id"] == categorise["participant_id"] == pid
    assert evolve["emotion"] == "happy"  # from the evolve result of the trial's record
    # a categorise trial's record has no face id and no emotion: the face is shown, not made
    assert categorise["final_face_id"] is None and categorise["emotion"] is None

    store = Store(url)
    tables = export_tables(store)
    sessions = tables["sessions"].query("participant_id == @pid")
    assert sessions["session_id"].tolist() == [evolve["session_id"]]
    sid = evolve["session_id"]
    assert str(int(sessions["seed"].iloc[0])) == evolve["session_seed"]
    trials = tables["trials"].query("session_id == @sid").set_index("trial")
    assert trials.loc[0, "task"] == "evolve" and trials.loc[1, "task"] == "categorise"
    assert str(int(trials.loc[0, "seed"])) == evolve["seed"]
    assert trials.loc[0, "final_face_id"] == evolve["final_face_id"]
    # every generation answered: the faces shown, the best and the others, in the export
    faces = tables["faces"].query("session_id == @sid and trial == 0")
    chosen = tables["selections"].query("session_id == @sid and trial == 0")
    assert [(g["attempt"], g["generation"]) for g in evolve["generations"]] == [
        (1, 0),
        (1, 1),
        (1, 2),
    ]
    assert [(r["attempt"], r["generation"]) for r in evolve["restarts"]] == [(0, 0)]
    for g in evolve["generations"]:
        shown = faces.query("attempt == @g['attempt'] and generation == @g['generation']")
        assert shown.sort_values("position")["face_id"].tolist() == g["shown"]
        rows = chosen.query(
            "attempt == @g['attempt'] and generation == @g['generation']"
        ).sort_values("rank")
        assert rows.query("role == 'elite'")["face_id"].tolist() == [g["elite"]]
        assert rows.query("role != 'elite'")["face_id"].tolist() == g["others"]
        assert rows["client_response_ms"].iloc[0] == pytest.approx(g["rt"])
    w_cols = [c for c in faces.columns if c.startswith("w_")]
    final = faces.query("attempt == 1 and face_id == @evolve['final_face_id']")
    np.testing.assert_allclose(
        final[w_cols].to_numpy(float)[-1], evolve["final_weights"], rtol=0, atol=0
    )
    ratings = tables["evolve_ratings"].query("session_id == @sid")
    assert ratings["value"].tolist() == [evolve["rating"]] == [6]
    # the categorise row's key (session, trial) finds the shown face's source in the export:
    # the participant's own final face of trial 0, which the page was never told
    responses = tables["categorise_responses"].query("session_id == @sid")
    assert responses["trial"].tolist() == [categorise["trial"]] == [1]
    assert responses["label"].tolist() == [categorise["label"]]
    assert responses["source"].tolist() == ["own"] and responses["source_trial"].tolist() == [0]
    assert responses["source_session_id"].tolist() == [sid]
    assert responses["source_face_id"].tolist() == [evolve["final_face_id"]]
    np.testing.assert_allclose(
        responses[w_cols].to_numpy(float)[0], categorise["final_weights"], atol=0
    )
    np.testing.assert_allclose(
        categorise["final_weights"], evolve["final_weights"], atol=0
    )  # own face
    report = replay_session(store, sid, ict_model.rig, ict_model.model_hash, model=ict_model)
    assert report.ok, report.mismatches
    store.dispose()


def kinds(value: Any) -> Any:
    """A value's shape: its JSON type, a list's length and its items' shapes, a dict's keys and
    their values' shapes (a number is a number, whole or not: JSON does not tell them apart)."""
    if isinstance(value, list):
        return ("list", len(value), sorted({repr(kinds(v)) for v in value}))
    if isinstance(value, dict):
        return {k: kinds(v) for k, v in value.items()}
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return type(value).__name__
    return "number"


def simulated_readme_page(server: str) -> str:
    """The README's page run by jsPsych's data-only simulation; its observer chooses two faces a
    generation, as run_readme_page's participant does."""
    page = local_page(readme_page(), server).replace("jsPsych.run([", "jsPsych.simulate([")
    page = page.replace('task: "evolve" }', 'task: "evolve", simulation_options: { chosen: 2 } }')
    head, tail = page.rsplit("  ]);", 1)
    return f'{head}  ], "data-only");{tail}'


def test_data_only_simulation_rows_have_the_real_rows_shape(
    browser: Any, site: ExperimentSite, server: tuple[ServerProcess, str]
) -> None:
    srv, url = server
    real = run_readme_page(
        open_page(browser, site.add("real.html", local_page(readme_page(), srv.url)), (1366, 768)),
        (1366, 768),
    )
    page = open_page(
        browser, site.add("simulated.html", simulated_readme_page(srv.url)), (1366, 768)
    )
    page.wait_for_selector("#jspsych-data-display", timeout=30_000)
    simulated = jspsych_data(page)
    page.context.close()
    assert [r["trial_type"] for r in simulated] == [r["trial_type"] for r in real]
    for got, want in zip(simulated[1:], real[1:], strict=True):  # the two emogen rows
        assert want["success"] and got["success"], got["reason"]
        assert (got["simulated"], want["simulated"]) == (True, False)
        # the restarts a participant makes are theirs: their number is no shape of the study
        assert set(got) == set(want)
        got_shape = {k: kinds(v) for k, v in got.items() if k != "restarts"}
        want_shape = {k: kinds(v) for k, v in want.items() if k != "restarts"}
        assert got_shape == want_shape, {
            k: (got_shape[k], want_shape[k]) for k in got_shape if got_shape[k] != want_shape[k]
        }
    evolve, categorise = simulated[1:]
    # what the study says (STUDY above), not what the plugin's options default to
    assert (evolve["study"], evolve["block_name"], evolve["emotion"]) == (
        "embedded",
        "make",
        "happy",
    )
    assert evolve["identity"] == "female-medium"
    assert len(evolve["generations"]) == STUDY["ga"]["generations"] + 1
    assert len(evolve["final_weights"]) == len(real[1]["final_weights"]) > 100
    assert (categorise["trial"], categorise["block_name"]) == (1, "recognise")
    assert sorted(categorise["labels"]) == sorted(STUDY["emotions"])
    # no session was made: the export has only the real page's participants
    store = Store(url)
    assert "simulated" not in set(export_tables(store)["sessions"]["participant_id"])
    store.dispose()


def failed(page: Any) -> dict[str, Any]:
    """The failed trial's reason as the page says it, then its data after Continue."""
    page.wait_for_selector(".emogen-trial[data-emogen-stage='failed']", timeout=60_000)
    said = page.inner_text("#failed-reason")
    page.click("#failed-continue")
    page.wait_for_function("window.done === true", timeout=30_000)
    (data,) = jspsych_data(page)
    assert data["success"] is False and "not your fault" in said  # the participant's words
    assert data["reason"] not in said  # the researcher's reason: in the data (and the console)
    return data


def test_a_page_of_an_origin_not_allowed_is_told_so(
    browser: Any, site: ExperimentSite, server: tuple[ServerProcess, str]
) -> None:
    srv, _url = server
    site.add("other.html", one_trial_page(srv.url, [{"task": "evolve", "patience_ms": 1500}]))
    page = open_page(browser, f"{site.other_origin}/other.html?PROLIFIC_PID=elsewhere", (1366, 768))
    data = failed(page)
    assert data["failure"] == "origin"
    assert f'add "{site.other_origin}" to embed_origins' in data["reason"]
    page.context.close()


def test_a_study_without_the_block_and_a_server_gone_mid_trial(
    browser: Any, site: ExperimentSite, tmp_path: Path, ict_dir: Path, viewer_bundle: Path
) -> None:
    study = {**STUDY, "name": "evolve-only", "blocks": [{"task": "evolve"}]}
    srv, url = serve(study, site, tmp_path, ict_dir)
    try:
        site.add(
            "categorise.html",
            one_trial_page(srv.url, [{"task": "categorise", "patience_ms": 1500}]),
        )
        page = open_page(
            browser, f"{site.origin}/categorise.html?PROLIFIC_PID=no-block", (1366, 768)
        )
        data = failed(page)
        assert data["failure"] == "block"
        assert (
            "the study 'evolve-only' has no categorise block (its blocks: block1 (evolve))"
            in data["reason"]
        )
        page.context.close()

        site.add("evolve.html", one_trial_page(srv.url, [{"task": "evolve", "patience_ms": 2500}]))
        page = open_page(browser, f"{site.origin}/evolve.html?PROLIFIC_PID=gone", (390, 844), True)
        wait_stage(page, "trial")
        srv.kill()  # the server dies while the faces are shown
        page.locator("#grid > .cell .face").nth(0).click()
        page.locator("#grid > .cell .face").nth(1).click()
        page.click("#next")
        page.wait_for_selector(".emogen-trial[data-emogen-stage='failed']", timeout=60_000)
        shot(page, "jspsych_server_gone_390x844.png")
        data = failed(page)
        assert data["failure"] == "unreachable" and "cannot be reached" in data["reason"]
        assert data["generations"] == []  # the server never took the selection
        page.context.close()
    finally:
        srv.stop()
    # nothing the server took is lost: the session and its first generation are in the export
    store = Store(url)
    tables = export_tables(store)
    sessions = tables["sessions"]
    assert set(sessions["participant_id"]) == {"gone"}  # the refused page made no session
    assert len(tables["faces"]) == 10 and len(tables["selections"]) == 0
    store.dispose()
