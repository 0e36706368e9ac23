"""The study's web server: FastAPI app factory, participant pages, researcher dashboard."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from fastapi import FastAPI


def create_app(*args: Any, **kwargs: Any) -> FastAPI:
    """See :func:`emogen.web.app.create_app` (imported lazily: FastAPI is an optional extra)."""
    from emogen.web.app import create_app as _create_app

    return _create_app(*args, **kwargs)


__all__ = ["create_app"]
