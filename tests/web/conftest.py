"""Shared fixtures of the web tests.

The study tests' fixtures live in ``tests/web/study_app.py`` and the viewer tests' in
``tests/web/viewer_site.py``; each test module imports the ones it uses.
"""

from collections.abc import Iterator
from typing import Any

import pytest


@pytest.fixture(scope="module")
def playwright_api() -> Iterator[Any]:
    """One Playwright driver per test module (a second sync_playwright() open at once in the
    same process would clash with the first's event loop), stopped at the module's end: while
    it runs, its event loop runs in this thread, and ``asyncio.run`` (a TestClient, a download)
    in a later module of the same pytest-xdist worker would fail with "cannot be called from a
    running event loop"."""
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        pytest.fail("browser tests need Playwright: pip install playwright (no browser download)")
    with sync_playwright() as p:
        yield p
