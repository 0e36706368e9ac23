"""Renderers shared by the render tests (one OpenGL context each, made once)."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from emogen.render.renderer import Renderer


@pytest.fixture(scope="session")
def renderer(ict_model) -> Iterator[Renderer]:  # type: ignore[no-untyped-def]
    """512×512, the default look."""
    with Renderer(ict_model) as r:
        yield r


@pytest.fixture(scope="session")
def small_renderer(ict_model) -> Iterator[Renderer]:  # type: ignore[no-untyped-def]
    with Renderer(ict_model, size=128) as r:
        yield r
