"""Step 2 in a real browser: a participant asks "Why?" of a step and "Why not…?" of the plan, and reads it."""

from __future__ import annotations

import pytest
from playwright.sync_api import Page, expect

from tests.service.pages.browsing import lamp_plan_shown, shoot


@pytest.mark.slow
def test_why_and_why_not_beside_the_robots_plan(live_server: str, page: Page) -> None:
    lamp_plan_shown(page, live_server)
    plan = page.locator("#plan-body")
    # The first plan of a new server also starts its planner worker: give it time on a busy machine.
    expect(plan).to_contain_text("Screw the light bulb into the base with cables.", timeout=60_000)

    plan.get_by_role("button", name="Why step 1?").click()
    expect(plan.locator(".why-answer").first).to_contain_text(
        "attaches the light bulb because the light bulb carries 'turn electricity into light'", timeout=30_000
    )
    plan.get_by_label("Ask the robot about the desk lamp:").fill("attach the shade")
    plan.get_by_role("button", name="Ask the robot").click()
    expect(plan.locator(".why-not-answer")).to_contain_text("does not need it for light", timeout=30_000)
    expect(plan.locator(".why-not-plan li")).to_have_text(
        ["Screw the light bulb into the base with cables.", "Clip the shade onto the base with cables."]
    )
    plan.get_by_label("Ask the robot about the desk lamp:").fill("attach the wick")
    plan.get_by_role("button", name="Ask the robot").click()
    expect(plan.locator(".why-not-answer")).to_contain_text("The desk lamp has no part 'the wick'", timeout=30_000)
    expect(plan.locator(".why-not-suggestions button")).to_have_count(3)  # the closest questions it can answer
    shoot(page, "participant-2-why-not")
