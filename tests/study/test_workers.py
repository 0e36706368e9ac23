"""Two server workers (each its own store: engine, locks, SQLite writer) over one database.

Whatever worker a step reaches, and however many times it arrives at once, it is stored once;
two different steps for the same shown generation: one is done, the other is a conflict.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator
from typing import Any

import pytest
from sqlalchemy import func, select

from emogen.study.config import StudyConfig
from emogen.study.errors import StepConflict
from emogen.study.sessions import StudyService
from emogen.study.storage import Store
from emogen.study.tables import StepRow
from emogen.tasks.evolve.tables import PopulationRow, SelectionRow
from tests.study.drive import choose, do, new_key, step_args, study_service


@pytest.fixture
def workers(db_url: str, small_study: StudyConfig, ict_model: Any) -> Iterator[list[StudyService]]:
    stores = [Store(db_url) for _ in range(2)]
    yield [study_service(small_study, store, ict_model) for store in stores]
    for store in stores:
        store.dispose()


def at_once(calls: list[Callable[[], Any]]) -> tuple[list[Any], list[BaseException]]:
    """Run the calls in threads released together; their results and errors."""
    barrier = threading.Barrier(len(calls))
    results: list[Any] = []
    errors: list[BaseException] = []

    def run(call: Callable[[], Any]) -> None:
        barrier.wait()
        try:
            results.append(call())
        except Exception as exc:  # collected for the assertions
            errors.append(exc)

    threads = [threading.Thread(target=run, args=(c,)) for c in calls]
    for t in threads:
        t.start()
    for t in threads:
        t.join(120)
    return results, errors


def count(store: Store, table: type, *where: Any) -> int:
    with store.read() as db:
        return int(db.scalar(select(func.count()).select_from(table).where(*where)) or 0)


def test_the_same_step_in_two_workers_is_stored_once(workers: list[StudyService]) -> None:
    token, _ = workers[0].create_session("W-1")
    state = do(workers[1], "begin", token, new_key())
    elite, others = choose(state)
    key, args = new_key(), step_args(state)
    results, errors = at_once(
        [
            lambda w=w: do(w, "select", token, key, **args, elite=elite, others=others)
            for w in (workers[0], workers[1], workers[0], workers[1])
        ]
    )
    assert errors == []
    assert sorted(bool(r.get("replayed", False)) for r in results) == [False, True, True, True]
    faces = {str(r["view"]["population"]) for r in results}
    assert len(faces) == 1  # every answer shows the one generation stored
    store = workers[0].store
    assert count(store, SelectionRow) == 1
    assert count(store, StepRow, StepRow.key == key) == 1
    assert count(store, PopulationRow, PopulationRow.generation == 1) == 1
    # both workers see the session where it is now
    assert (
        workers[0].state(token)
        == workers[1].state(token)
        == {k: v for k, v in results[0].items() if k != "replayed"}
    )


def test_two_different_steps_for_one_generation_one_wins(workers: list[StudyService]) -> None:
    token, _ = workers[0].create_session("W-2")
    state = do(workers[0], "begin", token, new_key())
    elite, others = choose(state)
    args = step_args(state)
    results, errors = at_once(
        [
            lambda: do(workers[0], "select", token, new_key(), **args, elite=elite, others=others),
            lambda: do(
                workers[1], "select", token, new_key(), **args, elite=others[0], others=[elite]
            ),
        ]
    )
    assert len(results) == 1 and len(errors) == 1
    assert isinstance(errors[0], StepConflict)
    assert count(workers[0].store, SelectionRow) == 1
    assert count(workers[0].store, PopulationRow, PopulationRow.generation == 1) == 1
