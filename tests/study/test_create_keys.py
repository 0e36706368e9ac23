"""A creation key is bound to the participant it first made a session for (issue #39): a retry
by that participant gets the session again, anyone else using the key is refused (409) and
sees nothing of it — an anonymous create included."""

from __future__ import annotations

import pytest

from emogen.study.errors import StepConflict
from emogen.study.sessions import StudyService

KEY = "k" * 24


@pytest.mark.parametrize("db_url", ["sqlite"], indirect=True)
def test_a_key_serves_only_the_participant_it_was_first_used_for(service: StudyService) -> None:
    token, _ = service.create_session("P1", create_key=KEY)
    again, _ = service.create_session("P1", create_key=KEY)  # a lost answer, retried
    assert again == token
    with pytest.raises(StepConflict, match="already started another participant's session"):
        service.create_session(None, create_key=KEY)  # before: P1's session, token and all
    with pytest.raises(StepConflict, match="already started another participant's session"):
        service.create_session("P2", create_key=KEY)  # before: a second session, same key
    assert service.participant_sources() == {"url": 1}  # nothing made by the refused tries


@pytest.mark.parametrize("db_url", ["sqlite"], indirect=True)
def test_an_anonymous_key_still_resumes_its_own_session(service: StudyService) -> None:
    token, _ = service.create_session(None, create_key=KEY)
    again, _ = service.create_session(None, create_key=KEY)
    assert again == token
    with pytest.raises(StepConflict, match="already started another participant's session"):
        service.create_session("P9", create_key=KEY)
