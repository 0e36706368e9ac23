"""Shared fixtures of the web tests.

The study tests' fixtures live in ``tests/web/study_app.py`` and the viewer tests' in
``tests/web/viewer_site.py``; each test module imports the ones it uses.
"""

from collections.abc import Iterator
from typing import Any

import pytest


@pytest.fixture(scope="session")
def playwright_api() -> Iterator[Any]:
    """One Playwright driver for the whole run (a second sync_playwright() in the same process
    would clash with the first's event loop)."""
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        pytest.fail("browser tests need Playwright: pip install playwright (no browser download)")
    with sync_playwright() as p:
        yield p
