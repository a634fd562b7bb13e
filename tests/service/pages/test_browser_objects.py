"""Step 1 of each new catalog object in a real browser: its explanation and a picture of every part, named.

Playwright drives Debian's Chromium headless against a live server; each object's step-1 page is
saved as a picture: in the test's own folder, or, with ``CAUSALPLAN_UPDATE_DOCS=1``, as
``docs/objects/<id>.png`` (the pictures the participant sees, kept with the docs). A test run
never changes the repository's files unasked.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest
from playwright.sync_api import Browser, Page, expect

from causalplan.objects.catalog import load_catalog
from tests.service.pages.browsing import LAPTOP
from tests.service.pages.flows import experiment, links

DOCS = Path(__file__).resolve().parents[3] / "docs" / "objects"
NEW_OBJECTS = ("headlamp", "solar_lantern", "oil_lamp", "gas_lantern")
CATALOG = load_catalog()

pytestmark = pytest.mark.slow


@pytest.fixture
def page(browser: Browser) -> Iterator[Page]:
    context = browser.new_context(viewport=LAPTOP)
    yield context.new_page()
    context.close()


@pytest.mark.parametrize("object_id", NEW_OBJECTS)
def test_step_one_shows_the_objects_explanation_and_each_part_pictured_and_named(
    live_server: str, page: Page, object_id: str, tmp_path: Path
) -> None:
    obj = CATALOG.get(object_id)
    other = "candle" if obj.category == "electric" else "flashlight"
    with httpx.Client(base_url=live_server, timeout=30) as client:
        made = experiment(client, conditions=[{"name": "one", "training": [object_id], "tests": [other]}])
        (participant,) = links(client, made["id"])
    page.goto(participant["url"])
    expect(page).to_have_url(re.compile(r"/step1/1$"))
    expect(page.locator("h1")).to_have_text(f"Step 1: what do the parts of the {obj.name} do?")
    expect(page.locator("main")).to_contain_text(obj.description.split(".")[0])
    pictures = page.locator(".part img")
    expect(pictures).to_have_count(len(obj.parts))
    for index, part in enumerate(obj.parts):
        picture = pictures.nth(index)
        expect(picture).to_have_attribute("alt", f"Picture of the {part.name}")
        picture.scroll_into_view_if_needed()  # the pictures load lazily
        expect(picture).to_have_js_property("complete", True, timeout=60_000)
        assert picture.evaluate("image => image.naturalWidth") > 0  # the simulator's picture arrived
        expect(page.get_by_label(f"Functions of the {part.name} (one per line)")).to_be_visible()
    folder = DOCS if os.environ.get("CAUSALPLAN_UPDATE_DOCS") == "1" else tmp_path
    folder.mkdir(parents=True, exist_ok=True)
    page.locator("main").screenshot(path=folder / f"{object_id}.png")
    assert (folder / f"{object_id}.png").stat().st_size > 0
