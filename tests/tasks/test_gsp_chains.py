# ruff: noqa: F811  (pytest fixtures imported by name, then requested by name)
"""GSP chains shared between sessions, exactly: the furthest-behind free chain, never a node
extended twice or skipped — under two workers and on PostgreSQL — an abandoned assignment
released after its timeout (the late answer kept, not applied), and aggregation's mean.

Every check reads the database itself (plain SQL through the store), not the task's code."""

from __future__ import annotations

import itertools
import threading
import time
from collections.abc import Iterator
from typing import Any

import pytest
from sqlalchemy import text

from emogen.study.config import study_from_dict
from emogen.study.storage import Store
from tests.study.drive import new_key, study_service
from tests.study_fixtures import db_url, pg_cluster  # noqa: F401


def gsp_study(**block: Any) -> Any:
    return study_from_dict(
        {
            "name": "gsp-chains",
            "emotions": ["happy"],
            "seed": 11,
            "correct": False,
            "blocks": [{"task": "gsp", "steps": 11, **block}],
        }
    )


def answer(service: Any, token: str, state: dict[str, Any], position: int = 7) -> dict[str, Any]:
    """The step a participant at this state sends: ask again while waiting, else a position."""
    trial = state["progress"]["trial"]
    if state["stage"] == "instructions":
        return service.step(token, {"command": "begin", "key": new_key()})
    if state["view"]["waiting"]:
        return service.step(token, {"command": "await_chain", "key": new_key(), "trial": trial})
    body = {"command": "slide", "key": new_key(), "trial": trial, "position": position}
    return service.step(token, body)


def answers(store: Store) -> list[dict[str, Any]]:
    """Every recorded answer with its chain and session, read with plain SQL."""
    query = text(
        "SELECT c.chain, i.iteration, i.member, i.applied, i.slider_value, i.node_value, "
        "i.genes_before, i.genes_after, i.dimension_index, t.session_id, t.position "
        "FROM gsp_iterations i JOIN gsp_chains c ON c.id = i.chain_id "
        "JOIN trials t ON t.id = i.trial_id ORDER BY c.chain, i.iteration, i.member"
    )
    with store.read() as db:
        return [dict(r._mapping) for r in db.execute(query)]


def chain_lengths(store: Store) -> dict[int, int]:
    with store.read() as db:
        return {
            int(c): int(n) for c, n in db.execute(text("SELECT chain, iterations FROM gsp_chains"))
        }


def check_chains(rows: list[dict[str, Any]], lengths: dict[int, int]) -> None:
    """Each chain's applied answers are its nodes 0…n-1, once each, and each node starts where
    the one before it ended (a plain loop over the records)."""
    import json

    for chain, n in lengths.items():
        applied = [r for r in rows if r["chain"] == chain and r["applied"]]
        assert [r["iteration"] for r in applied] == list(range(n)), (chain, applied)
        for a, b in itertools.pairwise(applied):
            after = json.loads(a["genes_before"])
            after[a["dimension_index"]] = a["node_value"]
            assert json.loads(b["genes_before"]) == pytest.approx(after, abs=1e-12)


@pytest.fixture
def two_workers(db_url: str, ict_model: Any) -> Iterator[list[Any]]:
    config = gsp_study(chains=4, iterations=3)
    stores = [Store(db_url) for _ in range(2)]
    yield [study_service(config, store, ict_model) for store in stores]
    for store in stores:
        store.dispose()


def test_twenty_participants_on_two_workers_extend_four_chains_exactly(
    two_workers: list[Any],
) -> None:
    errors: list[BaseException] = []
    barrier = threading.Barrier(20)
    polls = [0]

    def participant(i: int) -> None:
        try:
            token, state = two_workers[i % 2].create_session(f"P-{i:02d}")
            barrier.wait()
            k = 0
            while state["stage"] != "done":
                if state["stage"] == "trial" and state["view"]["waiting"]:
                    polls[0] += 1
                    time.sleep(0.02)
                k += 1  # each step to the other worker
                state = answer(two_workers[(i + k) % 2], token, state, position=i % 11)
        except BaseException as exc:  # collected for the assertion
            errors.append(exc)

    threads = [threading.Thread(target=participant, args=(i,)) for i in range(20)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(300)
    assert errors == []
    assert polls[0] > 0  # participants did wait for a chain held by others
    store = two_workers[0].store
    rows = answers(store)
    lengths = chain_lengths(store)
    assert len(rows) == 60 and all(r["applied"] for r in rows)  # 20 × 3, none late
    assert sum(lengths.values()) == 60 and set(lengths) == {0, 1, 2, 3}
    check_chains(rows, lengths)
    for sid in {r["session_id"] for r in rows}:  # never the same chain twice in a row
        mine = sorted((r["position"], r["chain"]) for r in rows if r["session_id"] == sid)
        assert all(a[1] != b[1] for a, b in itertools.pairwise(mine)), mine


def test_an_abandoned_node_is_released_after_its_timeout(db_url: str, ict_model: Any) -> None:
    store = Store(db_url)
    service = study_service(gsp_study(chains=2, iterations=1, release_after=1.0), store, ict_model)
    try:
        states = {}
        for who in ("A", "B", "C"):
            token, state = service.create_session(who)
            states[who] = (token, answer(service, token, state))
        assert not states["A"][1]["view"]["waiting"] and not states["B"][1]["view"]["waiting"]
        assert states["C"][1]["view"]["waiting"]  # both chains held
        assert states["C"][1]["view"]["frames"] == [] and states["C"][1]["view"]["face"] is None
        token_c = states["C"][0]
        still = answer(service, token_c, states["C"][1])
        assert still["view"]["waiting"]  # A's hold has not timed out yet
        time.sleep(1.1)
        given = answer(service, token_c, still)
        assert not given["view"]["waiting"]  # A's node, released
        assert given["view"]["frames"] == states["A"][1]["view"]["frames"]
        done = answer(service, token_c, given, position=3)
        assert done["stage"] == "done"
        late = answer(service, states["A"][0], states["A"][1], position=9)
        assert late["stage"] == "done"  # A's answer is taken and kept…
        answer(service, states["B"][0], states["B"][1], position=5)
        rows = answers(store)
        assert len(rows) == 3
        applied = [(r["chain"], r["iteration"], r["slider_value"]) for r in rows if r["applied"]]
        assert sorted(applied) == [(0, 0, pytest.approx(0.3)), (1, 0, pytest.approx(0.5))]
        assert [r["slider_value"] for r in rows if not r["applied"]] == [pytest.approx(0.9)]
        assert chain_lengths(store) == {0: 1, 1: 1}
    finally:
        store.dispose()


def test_aggregation_averages_answers_of_different_participants(
    db_url: str, ict_model: Any
) -> None:
    store = Store(db_url)
    service = study_service(gsp_study(chains=2, iterations=1, aggregation=2), store, ict_model)
    try:
        for who, position in (("A", 2), ("B", 4), ("C", 8), ("D", 10)):
            token, state = service.create_session(who)
            state = answer(
                service,
                token,
                service.step(token, {"command": "begin", "key": new_key()}),
                position,
            )
            assert state["stage"] == "done"
        rows = answers(store)
        lengths = chain_lengths(store)
        assert lengths == {0: 1, 1: 1}  # two answers per node: each chain one node on
        for chain in (0, 1):
            mine = [r for r in rows if r["chain"] == chain]
            assert [r["member"] for r in mine] == [0, 1]
            mean = (mine[0]["slider_value"] + mine[1]["slider_value"]) / 2
            assert mine[0]["node_value"] is None and mine[1]["node_value"] == pytest.approx(mean)
            assert len({r["session_id"] for r in mine}) == 2
        # the furthest-behind chain first: A and B went to different chains
        firsts = {r["chain"] for r in rows if r["member"] == 0}
        assert firsts == {0, 1}
    finally:
        store.dispose()
