"""Errors of a study's steps (the study server's and its tasks'); the web layer maps each to an
HTTP status (never 500)."""

from __future__ import annotations

from emogen.errors import EmoGenError


class StudyError(EmoGenError):
    """A request the study cannot carry out (HTTP 400 unless a subclass says otherwise)."""

    status = 400


class SessionNotFound(StudyError):
    """No session with that token (or id)."""

    status = 404


class StepConflict(StudyError):
    """The request does not fit the session's state: stale page, replayed or reused key."""

    status = 409


class Forbidden(StudyError):
    """Researcher endpoints without the right token, or a disabled action."""

    status = 403
