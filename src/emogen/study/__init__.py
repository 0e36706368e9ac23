"""Participant studies: config, sessions, storage (SQLAlchemy + Alembic), export, replay."""

from emogen.study.config import StudyConfig, load_study_config

__all__ = ["StudyConfig", "load_study_config"]
