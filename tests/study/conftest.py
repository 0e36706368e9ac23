# ruff: noqa: F811  (pytest fixtures imported by name, then requested by name)
"""Fixtures of the study tests: databases on both backends, a small two-trial study."""

from __future__ import annotations

from typing import Any

import pytest

from emogen.study.config import StudyConfig, study_from_dict
from tests.study.drive import study_service
from tests.study_fixtures import db_url, pg_cluster  # noqa: F401

SMALL_STUDY: dict[str, Any] = {
    "name": "small",
    "emotions": ["happy", "sad"],
    "seed": 1234,
    "completion": {"code": "DONE-42", "redirect_url": "https://example.org/done?cc={code}"},
    "ga": {"generations": 2, "min_selections": 1, "max_selections": 4},
}


@pytest.fixture
def small_study() -> StudyConfig:
    return study_from_dict(SMALL_STUDY)


@pytest.fixture
def service(db_url: str, small_study: StudyConfig, ict_model):  # type: ignore[no-untyped-def]
    from emogen.study.storage import Store

    store = Store(db_url)
    svc = study_service(small_study, store, ict_model)
    yield svc
    store.dispose()
