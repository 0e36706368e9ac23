# ruff: noqa: F811  (pytest fixtures imported by name, then requested by name)
"""A config edited under running sessions (issue 33): a text change orphans nobody, a design
change is refused unless the researcher says how running sessions continue, and a participant
id takes part once whatever version it began under; a retried create gets the same session."""

from __future__ import annotations

from typing import Any

import pytest

from emogen.errors import ConfigError
from emogen.study.config import study_from_dict
from emogen.study.errors import StepConflict
from emogen.study.storage import Store
from emogen.study.versions import changed_keys, design
from tests.study.conftest import SMALL_STUDY
from tests.study.drive import do, new_key, run_to_end, service_caller
from tests.study_fixtures import db_url, pg_cluster  # noqa: F401

FIXED_CONSENT = {
    **SMALL_STUDY,
    "consent": "A one-word fix of the consent text.",
    "rating": {"question": "How well does it show it?"},
}
NEW_DESIGN = {**SMALL_STUDY, "ga": {**SMALL_STUDY["ga"], "generations": 3}}


def serve(db_url: str, data: dict[str, Any], model: Any, **options: Any) -> Any:
    from emogen.study.sessions import StudyService

    store = Store(db_url)
    return StudyService(
        study_from_dict(data),
        store,
        model.rig,
        model_name=model.name,
        model_hash=model.model_hash,
        model=model,
        **options,
    )


def test_text_keys_leave_the_design_and_everything_else_is_named() -> None:
    old = study_from_dict(SMALL_STUDY).canonical_json()
    assert design(study_from_dict(FIXED_CONSENT).canonical_json()) == design(old)
    new = design(study_from_dict(NEW_DESIGN).canonical_json())
    assert changed_keys(design(old), new) == ["ga.generations"]


def test_a_text_change_keeps_running_sessions_going(db_url: str, ict_model: Any) -> None:
    first = serve(db_url, SMALL_STUDY, ict_model)
    token, state = first.create_session("V-1", create_key="v1-create-key-0001")
    state = do(first, "begin", token, new_key())
    first.store.dispose()
    second = serve(db_url, FIXED_CONSENT, ict_model)  # the consent's one-word fix
    assert second.ctx.study_id != first.ctx.study_id  # a new config row (its own hash) …
    resumed = second.state(token)  # … but the session goes on, with the new texts
    assert (
        resumed["progress"] == state["progress"]
        and resumed["view"]["population"] == state["view"]["population"]
    )
    again, _ = second.create_session("V-1", resume_token=token)
    assert again == token
    with pytest.raises(StepConflict, match="personal session link"):
        second.create_session("V-1")  # another browser still needs the link
    final = run_to_end(resumed, service_caller(second, token))
    assert final["stage"] == "done"
    assert second.participant_token("V-1") == token
    second.store.dispose()


def test_a_design_change_is_refused_while_sessions_run_unless_they_are_ended(
    db_url: str, ict_model: Any
) -> None:
    first = serve(db_url, SMALL_STUDY, ict_model)
    token, _ = first.create_session("V-2")
    do(first, "begin", token, new_key())
    done, state = first.create_session("V-3")
    run_to_end(state, service_caller(first, done))
    first.store.dispose()
    with pytest.raises(
        ConfigError, match=r"1 unfinished session .*ga\.generations.*--running-sessions end"
    ):
        serve(db_url, NEW_DESIGN, ict_model)
    second = serve(db_url, NEW_DESIGN, ict_model, running_sessions="end")
    assert second.ended == 1
    with pytest.raises(StepConflict, match="ended when the researcher changed the study's design"):
        second.state(token)
    for pid in ("V-2", "V-3"):  # no second session from scratch for either
        with pytest.raises(StepConflict, match="earlier version of this study"):
            second.create_session(pid)
    second.store.dispose()
    third = serve(db_url, NEW_DESIGN, ict_model)  # decided once: the next start needs no flag
    assert third.ended == 0
    third.store.dispose()


def test_a_retried_create_gets_the_same_session(db_url: str, ict_model: Any) -> None:
    svc = serve(db_url, SMALL_STUDY, ict_model)
    key = "retried-create-key-01"
    token, _ = svc.create_session("R-1", create_key=key)
    assert svc.create_session("R-1", create_key=key)[0] == token
    with pytest.raises(StepConflict, match="personal session link"):
        svc.create_session("R-1", create_key="another-browser-key-1")
    anonymous, _ = svc.create_session(None, create_key="anonymous-create-key-1")
    assert svc.create_session(None, create_key="anonymous-create-key-1")[0] == anonymous
    assert svc.create_session(None, create_key="anonymous-create-key-2")[0] != anonymous
    svc.store.dispose()
