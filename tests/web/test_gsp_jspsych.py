"""The jsPsych plugin runs GSP trials (the page's own component, tasks/gsp.js): two trials of a
study's GSP block on a lab's page of another origin, in Debian's Chromium; jsPsych's data and
``emogen study export`` agree trial for trial, and the session replays."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from benchmarks.jspsych_site import ExperimentSite, one_trial_page

from emogen.study.export import export_tables
from emogen.study.replay import replay_session
from emogen.study.storage import Store
from tests.web.test_jspsych_browser import jspsych_data, open_page, serve, site, wait_stage
from tests.web.test_study_browser import browser, viewer_bundle

pytestmark = [pytest.mark.browser, pytest.mark.slow]
_ = (browser, viewer_bundle, site)  # fixtures, requested by name

STUDY: dict[str, Any] = {
    "name": "embedded-gsp",
    "emotions": ["happy"],
    "identities": ["female-medium"],
    "seed": 43,
    "blocks": [{"task": "gsp", "chains": 2, "iterations": 2, "steps": 21}],
}


def test_the_plugin_runs_gsp_trials(
    browser: Any,
    site: ExperimentSite,
    tmp_path: Path,
    ict_dir: Path,
    ict_model: Any,
    viewer_bundle: Path,
) -> None:
    srv, url = serve(STUDY, site, tmp_path, ict_dir)
    try:
        trials = [{"task": "gsp"}, {"task": "gsp"}]
        site.add("gsp.html", one_trial_page(srv.url, trials))
        page = open_page(browser, f"{site.origin}/gsp.html?PROLIFIC_PID=plugin-gsp", (1366, 768))
        for _ in trials:
            wait_stage(page, "gsp")
            page.focus("#gsp-slider")
            page.keyboard.press("ArrowRight")
            page.keyboard.press("ArrowRight")
            page.click("#gsp-next")
        page.wait_for_function("window.done === true", timeout=60_000)
        data = jspsych_data(page)
        page.context.close()
    finally:
        srv.stop()
    assert [d["task"] for d in data] == ["gsp", "gsp"] and all(d["success"] for d in data)
    assert all(d["position"] == min(20, d["slider_start"] + 2) for d in data), data
    assert all(d["emotion"] == "happy" and len(d["final_weights"]) > 50 for d in data)
    store = Store(url)
    try:
        rows = export_tables(store)["gsp_iterations"].sort_values("trial")
        assert rows["trial"].tolist() == [d["trial"] for d in data]
        assert rows["position"].tolist() == [d["position"] for d in data]
        assert rows["slider_start"].tolist() == [d["slider_start"] for d in data]
        assert rows["slider_value"].tolist() == pytest.approx([d["value"] for d in data])
        sid = int(rows["session_id"].iloc[0])
        assert {d["session_id"] for d in data} == {sid}
        report = replay_session(store, sid, ict_model.rig, ict_model.model_hash, model=ict_model)
        assert report.ok and report.stimuli == 2, report.mismatches
    finally:
        store.dispose()
