"""The browser tests' fixtures: Playwright and one Chromium per module, and a laptop-sized page.

Playwright is imported only when a test asks for a browser: the fast lane collects this
folder's other tests without it.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import TYPE_CHECKING

import pytest

if TYPE_CHECKING:
    from playwright.sync_api import Browser, Page, Playwright


@pytest.fixture(scope="module")
def playwright() -> Iterator[Playwright]:
    from playwright.sync_api import sync_playwright

    with sync_playwright() as running:
        yield running


@pytest.fixture(scope="module")
def browser(playwright: Playwright) -> Iterator[Browser]:
    from tests.service.pages.browsing import CHROMIUM_ARGS, chromium_executable

    launched = playwright.chromium.launch(executable_path=chromium_executable(), args=CHROMIUM_ARGS)
    yield launched
    launched.close()


@pytest.fixture
def page(browser: Browser) -> Iterator[Page]:
    """A laptop-sized page that may download; the test fails if the page had a script error."""
    from tests.service.pages.browsing import LAPTOP, opened_page

    with opened_page(browser, viewport=LAPTOP, accept_downloads=True) as opened:
        yield opened
