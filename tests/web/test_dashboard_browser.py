# ruff: noqa: F811  (pytest fixtures imported by name, then requested by name)
"""The researcher dashboard in Chromium: sessions numbered as the export numbers them,
generations as the participant's page does, a participant's session link shown on request,
progress per condition, and every table downloaded (here: identities as Parquet)."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pandas as pd
import pytest
from benchmarks.bench_study import BENCH_TOKEN, ServerProcess, write_study_toml

from emogen.study.export import export_tables
from emogen.study.storage import Store
from tests.study.drive import new_key
from tests.study_fixtures import db_url, pg_cluster  # noqa: F401
from tests.web.test_study_browser import BROWSER_STUDY, browser  # noqa: F401

pytestmark = [pytest.mark.browser, pytest.mark.slow]


@pytest.fixture
def server(db_url: str, tmp_path: Path, ict_dir: Path) -> Iterator[ServerProcess]:
    config = write_study_toml(BROWSER_STUDY, tmp_path / "dash.toml")
    srv = ServerProcess(config, db_url, ict_dir, tmp_path / "server.log").start()
    yield srv
    srv.stop()


@pytest.mark.parametrize("db_url", ["sqlite"], indirect=True)
def test_dashboard_shows_the_participants_numbers_and_links(
    server: ServerProcess, browser: Any
) -> None:
    created = httpx.post(f"{server.url}/api/sessions", json={"participant_id": "DASH-1"}).json()
    token = created["token"]
    httpx.post(
        f"{server.url}/api/s/{token}/step", json={"command": "begin", "key": new_key()}
    ).raise_for_status()
    page = browser.new_page()
    page.goto(f"{server.url}/researcher")
    page.fill("#token", BENCH_TOKEN)
    page.click("#token-form button")
    row = page.locator("#sessions tbody tr", has_text="DASH-1")
    row.wait_for(timeout=20_000)
    cells = row.locator("td").all_inner_texts()
    store = Store(server.database_url, create=False)
    sessions = export_tables(store)["sessions"]
    store.dispose()
    mine = sessions[sessions["participant_id"] == "DASH-1"].iloc[0]
    # session_id and session_number as the export has them (before: "id" from 1 beside the
    # export's session_number from 0)
    assert cells[:3] == [str(mine["session_id"]), str(mine["session_number"]), "DASH-1"], cells
    # the page shows "Trial 1 of 2 · Generation 1 of 2" (ga.generations = 1)
    assert cells[4:6] == ["1 of 2", "1 of 2"], cells
    conditions = page.locator("#conditions tbody tr").all_inner_texts()
    assert len(conditions) == 2 and "happy" in conditions[0] and "sad" in conditions[1]
    with page.expect_download(timeout=60_000) as download:
        page.click('button[data-table="identities"][data-format="parquet"]')
    assert download.value.suggested_filename == "identities.parquet"
    identities = pd.read_parquet(download.value.path())
    assert identities["identity"].tolist() == ["generic"]
    assert token not in page.content()  # links only on request
    row.get_by_role("button", name="show link").click()
    field = row.get_by_role("textbox", name="session link of DASH-1")
    field.wait_for(timeout=10_000)
    assert field.input_value() == f"{server.url}/s/{token}"
    page.close()
