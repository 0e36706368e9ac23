# ruff: noqa: F811  (pytest fixtures imported by name, then requested by name)
"""Fault test of the gsp task, as tests/web/test_fault.py does the others: the server (one
worker, and two) is killed with SIGKILL between two slider answers and with an answer in
flight; resent with its key, the answer is done exactly once; every chain node is extended
once, none skipped, and the session replays."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import httpx
import pytest
from benchmarks.bench_study import ServerProcess, write_study_toml

from emogen.study.export import export_tables
from emogen.study.replay import replay_session
from emogen.study.storage import Store
from tests.study.drive import new_key
from tests.study_fixtures import db_url, pg_cluster  # noqa: F401
from tests.web.test_fault import kill_with_step_in_flight, post

pytestmark = pytest.mark.slow

STUDY: dict[str, Any] = {
    "name": "gsp-fault",
    "emotions": ["happy"],
    "seed": 4,
    "correct": False,
    "blocks": [{"task": "gsp", "chains": 2, "iterations": 4, "steps": 11}],
}


@pytest.mark.parametrize("workers", [1, 2])
def test_sigkill_between_and_during_answers_loses_and_duplicates_nothing(
    db_url: str, tmp_path: Path, ict_dir: Path, ict_model: Any, workers: int
) -> None:
    config = write_study_toml(STUDY, tmp_path / "study.toml")
    server = ServerProcess(config, db_url, ict_dir, tmp_path / "server.log", workers).start()

    def slide(state: dict[str, Any], key: str) -> dict[str, Any]:
        return {
            "command": "slide",
            "key": key,
            "trial": state["progress"]["trial"],
            "position": 3 + state["progress"]["trial"],
        }

    try:
        token = post(server.url, "/api/sessions", {"participant_id": "G-1"})["token"]
        state = post(server.url, f"/api/s/{token}/step", {"command": "begin", "key": new_key()})
        state = post(server.url, f"/api/s/{token}/step", slide(state, new_key()))
        server.kill()  # 1. between answers: the answer and the next node were committed
        server.start()
        assert httpx.get(f"{server.url}/api/s/{token}/state", timeout=30).json() == state
        body = slide(state, new_key())  # 2. killed with an answer in flight: done once
        kill_with_step_in_flight(server, f"/api/s/{token}/step", body)
        before = httpx.get(f"{server.url}/api/s/{token}/state", timeout=30).json()
        after = post(server.url, f"/api/s/{token}/step", body)
        moved = before["progress"]["trial"] != state["progress"]["trial"]
        assert after.get("replayed", False) == moved
        assert after["progress"]["trial"] == state["progress"]["trial"] + 1
        while after["stage"] != "done":
            after = post(server.url, f"/api/s/{token}/step", slide(after, new_key()))
    finally:
        server.stop()
    store = Store(db_url)
    try:
        rows = export_tables(store)["gsp_iterations"]
        assert len(rows) == 4 and not rows.duplicated(["trial"]).any()
        assert rows["position"].tolist() == [3, 4, 5, 6]
        for _, chain in rows.groupby("chain_id"):  # each node once, in order, none skipped
            chain = chain.sort_values("iteration")
            assert chain["iteration"].tolist() == list(range(len(chain)))
            for a, b in zip(chain.itertuples(), chain.iloc[1:].itertuples(), strict=False):
                face = json.loads(a.genes_before)
                face[a.dimension_index] = a.node_value
                assert json.loads(b.genes_before) == pytest.approx(face)
        report = replay_session(store, 1, ict_model.rig, ict_model.model_hash, model=ict_model)
        assert report.ok and report.stimuli == 4, report.mismatches
    finally:
        store.dispose()
