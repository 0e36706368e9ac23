"""The jsPsych plugin plays faces that move (the page's own evolve component and face display):
an evolve trial of a study's dynamic block on a lab's page of another origin, in Debian's
Chromium — the ten tiles play (their pixels change while nobody touches the page), "Play all
again" and the slider are there, a participant chooses through every generation and rates; the
export holds every face shown with its curves and says the 3D viewer showed them, and the
session replays."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from benchmarks.jspsych_site import ExperimentSite, one_trial_page

from emogen.study.export import export_tables
from emogen.study.replay import replay_session
from emogen.study.storage import Store
from tests.web.test_dynamic_browser import tiles
from tests.web.test_jspsych_browser import jspsych_data, open_page, serve, site, wait_stage
from tests.web.test_study_browser import browser, viewer_bundle

pytestmark = [pytest.mark.browser, pytest.mark.slow]
_ = (browser, viewer_bundle, site)  # fixtures, requested by name

STUDY: dict[str, Any] = {
    "name": "embedded-moving",
    "emotions": ["happy"],
    "seed": 7,
    "ga": {"generations": 1, "min_selections": 1, "max_selections": 3},
    "blocks": [{"task": "evolve", "dynamic": {}}],
}


def test_the_plugin_plays_moving_faces(
    browser: Any,
    site: ExperimentSite,
    tmp_path: Path,
    ict_dir: Path,
    ict_model: Any,
    viewer_bundle: Path,
) -> None:
    srv, url = serve(STUDY, site, tmp_path, ict_dir)
    try:
        site.add("moving.html", one_trial_page(srv.url, [{"task": "evolve"}]))
        page = open_page(
            browser, f"{site.origin}/moving.html?PROLIFIC_PID=plugin-moving", (1366, 768)
        )
        chosen = []
        for generation in (0, 1):
            wait_stage(page, "trial")
            assert page.locator("#grid > .cell .face").count() == 10
            if generation == 0:
                assert page.locator("#replay").is_visible() and page.locator("#scrub").count() == 1
                series = []  # over a loop and more (2 s clip + hold): the tiles move on their own
                for _ in range(9):
                    series.append(tiles(page))
                    page.wait_for_timeout(250)
                moved = [
                    max(np.abs(s[k] - series[0][k]).mean() for s in series[1:]) for k in range(10)
                ]
                assert sum(m > 0.05 for m in moved) >= 8, moved
            page.locator("#grid > .cell .face").nth(2).click()
            page.locator("#grid > .cell .face").nth(5).click()
            chosen.append(generation)
            page.click("#next")
        wait_stage(page, "rating")
        page.locator("#rating-scale").get_by_label("4", exact=True).check()
        page.click("#rate")
        page.wait_for_function("window.done === true", timeout=60_000)
        data = jspsych_data(page)
        page.context.close()
    finally:
        srv.stop()
    assert len(data) == 1 and data[0]["success"] and data[0]["display"] == "webgl", data
    assert [g["generation"] for g in data[0]["generations"]] == chosen
    store = Store(url)
    try:
        tables = export_tables(store)
        faces, curves, sel = tables["faces"], tables["face_curves"], tables["selections"]
        assert len(faces) == 20  # two generations of ten
        g_columns = [c for c in faces.columns if c.startswith("g_")]
        moving = faces[faces[g_columns].to_numpy().max(axis=1) > 0]
        assert set(zip(curves.generation, curves.face_id, strict=True)) == set(
            zip(moving.generation, moving.face_id, strict=True)
        )
        assert sel.fallback.tolist() == [False] * len(sel)  # the 3D viewer's clips
        assert sorted(set(sel.generation)) == chosen
        sid = int(sel["session_id"].iloc[0])
        report = replay_session(store, sid, ict_model.rig, ict_model.model_hash, model=ict_model)
        assert report.ok, report.mismatches
    finally:
        store.dispose()
