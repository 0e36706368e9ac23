"""Which display showed an evolve step's faces (``fallback``: the server's images, not the 3D
viewer) is recorded with the selection, the restart and the rating as the page sent it,
exported as a nullable boolean (NA where the page did not say), and a bad value is refused by
name with nothing recorded. The browser's own sending is tested in
tests/web/test_dynamic_browser.py (WebGL and ``?render=png``)."""

from __future__ import annotations

from typing import Any

import pandas as pd
import pytest

from emogen.errors import ConfigError
from emogen.study.export import export_tables
from emogen.study.sessions import StudyService
from tests.study.drive import choose, do, new_key, step_args


def test_the_display_of_each_step_is_recorded_and_exported(service: StudyService) -> None:
    token, _ = service.create_session("FALLBACK-1")
    state = do(service, "begin", token, new_key())
    elite, others = choose(state)
    key = new_key()
    body = {**step_args(state), "elite": elite, "others": others, "fallback": True}
    state = do(service, "select", token, key, **body)
    # the same key again is the same step (its answer, nothing stored twice) …
    again = do(service, "select", token, key, **body)
    assert again.pop("replayed") is True and again == state
    # … and a bad value is refused by name, with nothing recorded
    elite, others = choose(state)
    with pytest.raises(ConfigError, match=r"fallback.*got 'yes'"):
        do(service, "select", token, new_key(), **step_args(state), elite=elite, fallback="yes")
    state = do(service, "restart", token, new_key(), **step_args(state), fallback=False)
    for _ in range(3):  # generations 0–2 of the new attempt: a page that does not say
        elite, others = choose(state)
        state = do(service, "select", token, new_key(), **step_args(state), elite=elite)
    assert state["trial"]["status"] == "rating"
    do(service, "rate", token, new_key(), trial=0, value=3, fallback=True)

    tables = export_tables(service.store)
    sel = tables["selections"].sort_values(["attempt", "generation", "rank"])
    assert str(sel.fallback.dtype) == "boolean"
    by_step = sel.groupby(["attempt", "generation"]).fallback.agg(lambda s: s.tolist())
    assert by_step[(0, 0)] == [True] * 3  # the three faces chosen in one step
    assert all(all(v is pd.NA for v in by_step[(1, g)]) for g in (0, 1, 2)), by_step
    assert len(by_step) == 4  # the refused step left no row
    restarts = tables["restarts"]
    assert restarts.fallback.tolist() == [False]
    ratings = tables["evolve_ratings"]
    assert ratings.fallback.tolist() == [True]


def test_an_answer_without_it_is_the_answer_recorded_before(service: StudyService) -> None:
    """A step sent without ``fallback`` hashes as before it existed: a key recorded by an older
    page, sent again by it, is the same step."""
    from emogen.tasks.registry import parse_command

    body: dict[str, Any] = {"command": "select", "key": new_key(), "trial": 0, "attempt": 0,
                            "generation": 0, "elite": 1, "others": [2]}  # fmt: skip
    assert "fallback" not in parse_command(body).payload()
    assert parse_command({**body, "fallback": False}).payload()["fallback"] is False
