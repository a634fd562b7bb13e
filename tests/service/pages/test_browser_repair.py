"""The research page "Watch the robot repair an object" in a real browser: the 3D player on a repair."""

from __future__ import annotations

from collections.abc import Iterator

import httpx
import pytest
from playwright.sync_api import Page, expect

from tests.service.fixtures import AUTH, serving, settings_for, sqlite_url
from tests.service.pages.browsing import shoot, signed_in

pytestmark = pytest.mark.slow  # the robot carries out an episode, and a real Chromium plays it

PLAYER = "document.querySelector('#repair-player > div').player"


@pytest.fixture(scope="module")
def repair_server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    url = sqlite_url(tmp_path_factory.mktemp("db"))
    with serving(settings_for(url)) as base:
        yield base


def test_the_researcher_watches_the_robot_repair_the_desk_lamp(repair_server: str, page: Page) -> None:
    signed_in(page, repair_server)
    page.get_by_role("link", name="Robot repairs").click()
    expect(page.locator("h1")).to_have_text("Watch the robot repair an object")
    page.get_by_label("The broken part").select_option("desk_lamp/light_bulb")
    page.get_by_label("Whose policy the robot follows").select_option("oracle")
    page.get_by_role("button", name="Watch the robot repair it").click()
    canvas = page.locator("#repair-player canvas")
    expect(canvas).to_have_count(1, timeout=120_000)
    page.wait_for_function(f"() => {PLAYER}.state().frames > 0")  # its first frame is drawn
    expect(page.locator("#repair-status")).to_have_text("The robot repaired the desk lamp in 7 actions.")

    # Each action of the episode, in order; the first plays, what each observed shows once reached.
    actions = page.get_by_role("list", name="The robot's actions").locator("li")
    expect(actions).to_have_count(7)
    expect(actions.nth(0)).to_have_attribute("aria-current", "step")
    expect(actions.nth(1)).to_have_text("inspect light bulb: broken", use_inner_text=True)
    expect(actions.nth(6)).to_have_text("test", use_inner_text=True)  # not reached: no outcome shown yet

    page.evaluate(f"{PLAYER}.seek({PLAYER}.state().seconds)")
    page.wait_for_function(f"() => {PLAYER}.state().action === 7")
    expect(actions.nth(6)).to_have_text("test: goal", use_inner_text=True)
    expect(actions.nth(6)).to_have_attribute("aria-current", "step")
    expect(page.locator("#repair-player li.done")).to_have_count(6)
    shoot(page, "research-3-watch-the-robot-repair")

    # The player's last frame puts every body where the robot's run left it: the spare on the lamp.
    job = page.evaluate("performance.getEntriesByType('resource').map((r) => r.name)")
    (played,) = [url for url in job if url.endswith("/playback")]
    with httpx.Client(timeout=60) as client:
        document = client.get(played, headers=AUTH).json()
    state = page.evaluate(f"{PLAYER}.state()")
    for body, pose in document["assembled"].items():
        assert max(abs(a - b) for a, b in zip(state["parts"][body], pose, strict=True)) < 1e-4, body
