"""Exact counterbalancing (``counterbalance = "arrival"``): Latin-square rows in arrival order,
counted under the study's lock, beside the hashed rows (balanced in expectation only)."""

from __future__ import annotations

from collections import Counter
from typing import Any

import pytest

from emogen.study.config import study_from_dict
from emogen.study.dashboard import overview
from emogen.study.design import balanced_latin_square
from emogen.study.export import export_tables
from emogen.study.replay import replay_session
from emogen.study.storage import Store
from tests.study.drive import run_to_end, service_caller, study_service
from tests.study.test_workers import at_once

LATIN = {
    "name": "latin",
    "emotions": ["happy", "sad", "angry", "fearful"],
    "order": "latin_square",
    "seed": 7,
    "ga": {"generations": 1, "min_selections": 1, "max_selections": 4},
}
N_ROWS = len(balanced_latin_square(4))  # 4 conditions: 4 rows


def _rows(store: Store) -> dict[str, int]:
    """Each participant's Latin-square row, read from the export's sessions table."""
    sessions = export_tables(store)["sessions"]
    return {
        p: int(r) for p, r in zip(sessions["participant_id"], sessions["order_row"], strict=True)
    }


@pytest.mark.parametrize("db_url", ["sqlite"], indirect=True)
def test_three_participants_get_rows_0_1_2(db_url: str, ict_model: Any) -> None:
    store = Store(db_url)
    try:
        service = study_service(
            study_from_dict({**LATIN, "counterbalance": "arrival"}), store, ict_model
        )
        tokens = [service.create_session(f"P-{k}")[0] for k in range(3)]
        assert _rows(store) == {"P-0": 0, "P-1": 1, "P-2": 2}
        # the trial order is that row of the square (conditions in config order)
        trials = export_tables(store)["trials"]
        first = trials[trials["participant_id"] == "P-1"].sort_values("trial")
        assert first["condition"].tolist() == balanced_latin_square(4)[1]
        # a session replays from what was stored, whatever the assignment
        run_to_end(service.state(tokens[1]), service_caller(service, tokens[1]))
        sid = int(trials[trials["participant_id"] == "P-1"]["session_id"].iloc[0])
        report = replay_session(store, sid, ict_model.rig, ict_model.model_hash, model=ict_model)
        assert report.ok and report.mismatches == [] and report.populations == 4 * 2
        # the dashboard's row counts are the export's
        counts = overview(store, service.ctx.config, service.ctx.accepted)["counterbalancing"]
        assert counts["counterbalance"] == "arrival"
        by_row = Counter(_rows(store).values())
        assert [r["sessions"] for r in counts["rows"]] == [by_row[r] for r in range(N_ROWS)]
        assert [r["done"] for r in counts["rows"]] == [0, 1, 0, 0]
    finally:
        store.dispose()


@pytest.mark.parametrize("db_url", ["sqlite"], indirect=True)
def test_hashed_rows_are_the_default_and_not_arrival_order(db_url: str, ict_model: Any) -> None:
    store = Store(db_url)
    try:
        service = study_service(study_from_dict(LATIN), store, ict_model)
        for k in range(8):
            service.create_session(f"P-{k}")
        rows = _rows(store)
        # the hash's rows (the same for a participant whoever came first): not 0, 1, 2, 3 …
        assert [rows[f"P-{k}"] for k in range(8)] != [k % N_ROWS for k in range(8)]
        assert (
            overview(store, service.ctx.config, service.ctx.accepted)["counterbalancing"][
                "counterbalance"
            ]
            == "hash"
        )
    finally:
        store.dispose()


def test_concurrent_arrivals_in_two_workers_stay_balanced(db_url: str, ict_model: Any) -> None:
    config = study_from_dict({**LATIN, "counterbalance": "arrival"})
    stores = [Store(db_url) for _ in range(2)]
    try:
        workers = [study_service(config, store, ict_model) for store in stores]
        calls = [lambda k=k: workers[k % 2].create_session(f"C-{k}") for k in range(2 * N_ROWS)]
        results, errors = at_once(calls)
        assert errors == [] and len(results) == 2 * N_ROWS
        rows = _rows(stores[0])
        assert sorted(Counter(rows.values()).items()) == [(r, 2) for r in range(N_ROWS)]
        numbers = export_tables(stores[0])["sessions"]["session_number"].tolist()
        assert sorted(numbers) == list(range(2 * N_ROWS))  # each arrival counted once
    finally:
        for store in stores:
            store.dispose()
