"""A selection's next generation made ahead of the write transaction (docs/study.md, "Corrected
ahead"): the step answers and records the same as without it, bit for bit, and every way the
work ahead can go wrong (a stale request, a repeated key, two tabs, an error in it) ends in the
step's own outcome.

The references are a study service whose steps do nothing ahead (``SessionSteps._ahead``
replaced) and :func:`emogen.correct.correct_faces` called directly.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import emogen.correct.faces as faces_module
from emogen.ga.corrector import AHEAD_KEPT, ModelCorrector, corrected_ahead
from emogen.study.config import study_from_dict
from emogen.study.errors import StepConflict
from emogen.study.steps import SessionSteps
from emogen.study.storage import Store
from emogen.tasks.evolve.task import EvolveTask
from emogen.tasks.registry import parse_command
from tests.study.drive import (
    choose,
    command,
    do,
    new_key,
    run_to_end,
    service_caller,
    step_args,
    study_service,
)

MOVING: dict[str, Any] = {
    "name": "ahead",
    "emotions": ["happy", "sad"],
    "seed": 2024,
    "ga": {"generations": 2, "min_selections": 1, "max_selections": 4},
    "blocks": [{"task": "evolve", "dynamic": {}}],
}
STILL: dict[str, Any] = {**MOVING, "name": "ahead-still", "blocks": [{"task": "evolve"}]}


@contextmanager
def _service(study: dict[str, Any], path: Path, model: Any) -> Iterator[Any]:
    store = Store(f"sqlite:///{path}")
    try:
        yield study_service(study_from_dict(study), store, model)
    finally:
        store.dispose()


@contextmanager
def _corrections() -> Iterator[list[str]]:
    """The names of the threads that corrected a batch of faces, in order."""
    calls: list[str] = []
    real = faces_module.correct_faces

    def counted(*args: Any, **kwargs: Any) -> Any:
        calls.append(threading.current_thread().name)
        return real(*args, **kwargs)

    faces_module.correct_faces = counted
    try:
        yield calls
    finally:
        faces_module.correct_faces = real


def _select(service: Any, token: str, state: dict[str, Any], key: str | None = None) -> Any:
    elite, others = choose(state)
    return do(service, "select", token, key or new_key(), **step_args(state), elite=elite,
              others=others, response_ms=900.0)  # fmt: skip


def _walk(service: Any, *, whole: bool = False) -> list[dict[str, Any]]:
    """One participant's selections through the first trial (``whole``: then on to the end of
    the session: the rating, the second trial, done): the state after each step."""
    token, _ = service.create_session("p-ahead")
    state = do(service, "begin", token, new_key())
    states = [state]
    while state["trial"]["status"] == "active" and state["progress"]["trial"] == 0:
        state = _select(service, token, state)
        states.append(state)
    if whole:
        states += _finished(service, token, state)
    return states


def _finished(service: Any, token: str, state: dict[str, Any]) -> list[dict[str, Any]]:
    """The session driven to its end from ``state``: the state after each step, the last one
    done."""
    states: list[dict[str, Any]] = []

    def call(kind: str, body: dict[str, Any]) -> dict[str, Any]:
        states.append(service_caller(service, token)(kind, body))
        return states[-1]

    run_to_end(state, call)
    assert states[-1]["stage"] == "done"
    return states


def _shown(states: list[dict[str, Any]]) -> list[Any]:
    """What each state showed: the population's faces (weights, motion with its keyframe
    correctives), without the session's clock."""
    out = []
    for s in states:
        pop = (s.get("view") or {}).get("population")
        out.append(None if pop is None else pop["faces"])
    return out


@pytest.mark.parametrize("study", [MOVING, STILL], ids=["moving", "still"])
def test_steps_answer_as_without_the_work_ahead(
    study: dict[str, Any], tmp_path: Path, ict_model: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    with monkeypatch.context() as m:
        m.setattr(SessionSteps, "_ahead", lambda self, token, cmd: None)
        with _service(study, tmp_path / "plain.sqlite", ict_model) as plain:
            reference = _walk(plain)
    with _service(study, tmp_path / "ahead.sqlite", ict_model) as ahead, _corrections() as calls:
        states = _walk(ahead)
    assert len(states) == len(reference) == 4  # generations 0, 1, 2, then the rating
    assert _shown(states) == _shown(reference)
    writer = [name for name in calls if name == "emogen-sqlite-writer"]
    if study is MOVING:
        # generation 0 is made at the trial's start, in the writer (the faces, then their
        # keyframes); each selection's generation, and after the last the final face, is
        # corrected ahead and not again
        assert len(writer) == 2 and len(calls) == 8
    else:  # still faces are not worked ahead: every correction in the writer, once
        assert writer == calls and len(calls) == 4


def test_a_kept_correction_is_the_correction_of_those_weights(
    ict_model: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    rng = np.random.default_rng(5)
    weights = np.zeros((6, ict_model.n_shapes))
    weights[:, rng.choice(ict_model.n_shapes, 12, replace=False)] = rng.uniform(0, 0.9, (6, 12))
    reference = faces_module.correct_faces(ict_model, weights)
    corrector = ModelCorrector(ict_model)
    with corrected_ahead():
        corrector(weights)
    with _corrections() as calls:
        names, values = corrector(weights.copy())  # equal weights, another array
        assert calls == []  # answered from what was kept
        assert names == tuple(reference.corrective_names)
        assert np.array_equal(values, reference.correctives)
        corrector(weights)  # kept for one call only
        assert len(calls) == 1
        with corrected_ahead():
            corrector(weights)
        nudged = weights.copy()
        nudged[0, 0] = np.nextafter(nudged[0, 0], 1.0)  # one bit apart: not the same weights
        corrector(nudged)
        assert len(calls) == 3
        corrector(weights[:3])  # a different batch of the same rows
        assert len(calls) == 4


def test_kept_corrections_are_bounded_oldest_first(ict_model: Any) -> None:
    corrector = ModelCorrector(ict_model)
    batches = [np.full((1, ict_model.n_shapes), i / 200) for i in range(AHEAD_KEPT + 5)]
    with corrected_ahead():
        for w in batches:
            corrector(w)
    assert len(corrector._kept) == AHEAD_KEPT
    with _corrections() as calls:
        corrector(batches[0])  # evicted: corrected again
        corrector(batches[-1])  # kept
    assert len(calls) == 1


def test_stale_repeated_and_raced_requests_end_as_steps_do(
    tmp_path: Path, ict_model: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    with monkeypatch.context() as m:
        m.setattr(SessionSteps, "_ahead", lambda self, token, cmd: None)
        with _service(MOVING, tmp_path / "plain.sqlite", ict_model) as plain:
            reference = _walk(plain, whole=True)
    with _service(MOVING, tmp_path / "ahead.sqlite", ict_model) as service:
        token, _ = service.create_session("p-ahead")
        state0 = do(service, "begin", token, new_key())
        elite, others = choose(state0)
        body = {**step_args(state0), "elite": elite, "others": others, "response_ms": 900.0}
        # another tab's selection of the same generation (other faces), worked ahead, then
        # this tab's selection commits first: the other one is refused as stale when it comes
        ids = [f["id"] for f in state0["view"]["population"]["faces"]]
        other = {**step_args(state0), "elite": ids[-1], "others": [], "response_ms": 900.0}
        tab2 = command("select", {"key": new_key(), **other})
        service.steps._ahead(token, parse_command(tab2))
        key = new_key()
        state1 = do(service, "select", token, key, **body)
        with pytest.raises(StepConflict, match="generation 0"):
            service.step(token, tab2)
        assert _shown([state1]) == _shown([reference[1]])
        # the same key again: the recorded answer, nothing made ahead or in the writer
        with _corrections() as calls:
            again = do(service, "select", token, key, **body)
        assert calls == [] and again["replayed"] is True
        # a selection for a generation no longer shown: refused, nothing corrected
        with _corrections() as calls, pytest.raises(StepConflict, match="generation 0"):
            do(service, "select", token, new_key(), **body)
        assert calls == []
        state2 = _select(service, token, state1)
        assert _shown([state2]) == _shown([reference[2]])
        # and the rest of the session as without any of it: the rating, the second trial, done
        assert _shown(_finished(service, token, state2)) == _shown(reference[3:])


def test_an_error_in_the_work_ahead_leaves_the_step_to_itself(
    tmp_path: Path, ict_model: Any, monkeypatch: pytest.MonkeyPatch, caplog: Any
) -> None:
    with monkeypatch.context() as m:
        m.setattr(SessionSteps, "_ahead", lambda self, token, cmd: None)
        with _service(MOVING, tmp_path / "plain.sqlite", ict_model) as plain:
            reference = _walk(plain, whole=True)

    def broken(*args: Any) -> None:
        raise RuntimeError("ahead broke")

    monkeypatch.setattr(EvolveTask, "ahead", broken, raising=False)
    with (
        _service(MOVING, tmp_path / "ahead.sqlite", ict_model) as service,
        caplog.at_level(logging.WARNING, logger="emogen.study.steps"),
    ):
        states = _walk(service, whole=True)  # the steps after it too: on to the session's end
    assert states[-1]["stage"] == "done"
    assert _shown(states) == _shown(reference)
    assert "step ahead of select failed; the step goes on" in caplog.text
    assert "ahead broke" in caplog.text
