# ruff: noqa: F811  (pytest fixtures imported by name, then requested by name)
"""Fixtures of the study web tests (imported by each test module): the app on both backends."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest
from fastapi.testclient import TestClient

from tests.study.conftest import SMALL_STUDY
from tests.study_fixtures import db_url, pg_cluster  # noqa: F401

RESEARCHER_TOKEN = "researcher-secret-0123456789-abcdefghij"


@pytest.fixture
def app(db_url: str, ict_model):  # type: ignore[no-untyped-def]
    from emogen.study.config import study_from_dict
    from emogen.web import create_app
    from emogen.web.ratelimit import RateLimit

    application = create_app(
        study_from_dict(SMALL_STUDY),
        db_url,
        model=ict_model,
        researcher_token=RESEARCHER_TOKEN,
        # these tests make many sessions from one address: the limit has its own tests
        session_limit=RateLimit.parse("off"),
    )
    yield application
    application.state.store.dispose()


@pytest.fixture
def client(app: Any) -> Iterator[TestClient]:
    with TestClient(app) as c:
        yield c
