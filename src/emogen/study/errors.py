"""Errors of the study server (:mod:`emogen.tasks.errors`, where its tasks raise them too)."""

from __future__ import annotations

from emogen.tasks.errors import Forbidden, SessionNotFound, StepConflict, StudyError

__all__ = ["Forbidden", "SessionNotFound", "StepConflict", "StudyError"]
